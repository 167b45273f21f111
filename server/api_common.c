#include "api_common.h"

#include <stdio.h>

#include "app.h"

int api_status(int code)
{
    switch (code) {
    case GLINT_ENOTFOUND: return 404;
    case GLINT_EINVAL:
    case GLINT_EFORMAT:
    case GLINT_ENONFINITE:
    case GLINT_ERANGE:
    case GLINT_EUNSUPPORTED: return 422;
    default: return 500;
    }
}

http_resp api_fail(const glint_err *e, const char *context)
{
    int st = api_status(e->code);
    const char *slug = st == 404 ? "not-found" : st == 422 ? "invalid-input" : NULL;
    if (st == 500)
        fprintf(stderr, "glintd: %s: %s\n", context, e->msg);
    return http_problem(st, slug, "%s: %s", context, e->msg);
}

http_resp api_body_too_large(http_req *req, const char *what)
{
    app *a = req->app;
    return http_problem(413, "body-too-large",
                        "%s exceeds the request body limit of %zu bytes (max_body, glintd "
                        "--max-body-mb %zu)",
                        what, a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
}
