/* api_common.h: answers shared by the api_* handler modules. */
#ifndef GLINTD_API_COMMON_H
#define GLINTD_API_COMMON_H

#include "err.h"
#include "http.h"

/* The HTTP status for a glint error code: the client's mistakes are 4xx
 * (ENOTFOUND 404; EINVAL, EFORMAT, ENONFINITE, ERANGE, EUNSUPPORTED 422),
 * anything else 500 (logged). */
int api_status(int code);

/* A problem response for a glint error: "<context>: <message>". */
http_resp api_fail(const glint_err *e, const char *context);

/* 413 naming the body limit and the option that sets it. */
http_resp api_body_too_large(http_req *req, const char *what);

#endif
