/* http_origin.h: which web origins may call the API, and the answer to a
 * preflight (http.h, http_config.allow_origin, says the policy).  Part of
 * http.c, apart for size. */
#ifndef GLINTD_HTTP_ORIGIN_H
#define GLINTD_HTTP_ORIGIN_H

#include "http.h"

/* Whether Origin ("scheme://host[:port]") is the daemon's own: the Host
 * the request was sent to (NULL: none), under http or https. */
int http_same_origin(const char *origin, const char *host);

/* Whether Origin is one of the comma-separated `list` (exact, case-blind;
 * NULL: none). */
int http_origin_allowed(const char *list, const char *origin);

/* 204 to OPTIONS: the methods, and for an admitted origin (cors 1) what a
 * preflight asks (methods, headers, how long to keep the answer). */
http_resp http_preflight(int cors);

#endif
