/* http_origin.c: which web origins may call the API (http_origin.h). */
#include "http_origin.h"

#include <string.h>
#include <strings.h>

#include <microhttpd.h>

/* Whether Origin ("scheme://host[:port]") is the daemon's own: the Host
 * the request was sent to, under http or https. */
int http_same_origin(const char *origin, const char *host)
{
    const char *h = strstr(origin, "://");
    if (!host || !h || (strncmp(origin, "http://", 7) && strncmp(origin, "https://", 8)))
        return 0;
    return strcasecmp(h + 3, host) == 0;
}

/* Whether Origin is one of the comma-separated `list` (exact, case-blind). */
int http_origin_allowed(const char *list, const char *origin)
{
    size_t n = strlen(origin);
    while (list && *list) {
        const char *end = strchr(list, ',');
        size_t len = end ? (size_t)(end - list) : strlen(list);
        while (len && (*list == ' ')) list++, len--;
        while (len && list[len - 1] == ' ') len--;
        if (len == n && n > 0 && strncasecmp(list, origin, n) == 0)
            return 1;
        list = end ? end + 1 : NULL;
    }
    return 0;
}

/* OPTIONS: what the API takes (cors: for an admitted origin's preflight). */
http_resp http_preflight(int cors)
{
    http_resp r = {204, MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT)};
    if (!r.r)
        return r;
    MHD_add_response_header(r.r, MHD_HTTP_HEADER_ALLOW, "GET, HEAD, POST, PUT, DELETE, OPTIONS");
    if (cors) {
        MHD_add_response_header(r.r, "Access-Control-Allow-Methods",
                                "GET, HEAD, POST, PUT, DELETE");
        MHD_add_response_header(r.r, "Access-Control-Allow-Headers",
                                "Content-Type, Authorization, X-Api-Key, X-Glint-Token, "
                                "X-Glint-Owner, If-Match, Last-Event-ID");
        MHD_add_response_header(r.r, "Access-Control-Max-Age", "600");
    }
    return r;
}
