/* http_origin.h: which Host names glintd answers, which web origins may
 * call the API, and the answer to a preflight (http.h, http_config.allow_origin, says the policy).  Part of
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

/* Whether glintd answers a request whose Host header is `host` (http.h,
 * http_config.allow_host says the policy): an IP address literal
 * ("192.0.2.7", "[::1]", with or without ":port"), "localhost", or a name
 * in the comma-separated `allow` (case-blind; an entry with a port
 * matches that port only; NULL: none); "*" as `allow` admits any Host.
 * A malformed Host (an empty name, a bad port) is not served. */
int http_host_served(const char *host, const char *allow);

/* 204 to OPTIONS: the methods, and for an admitted origin (cors 1) what a
 * preflight asks (methods, headers, how long to keep the answer). */
http_resp http_preflight(int cors);

#endif
