/* http_origin.c: which web origins may call the API (http_origin.h). */
#include "http_origin.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <string.h>
#include <strings.h>

#include <microhttpd.h>

/* Whether the `len` bytes at s are one of the comma-separated `list`
 * (case-blind, blanks around entries ignored). */
static int listed(const char *list, const char *s, size_t len)
{
    while (list && *list) {
        const char *end = strchr(list, ',');
        size_t n = end ? (size_t)(end - list) : strlen(list);
        while (n && *list == ' ')
            list++, n--;
        while (n && list[n - 1] == ' ')
            n--;
        if (n == len && len > 0 && strncasecmp(list, s, len) == 0)
            return 1;
        list = end ? end + 1 : NULL;
    }
    return 0;
}

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
    return listed(list, origin, strlen(origin));
}

/* Whether `port` (len bytes) is empty or ":" and digits. */
static int port_ok(const char *port, size_t len)
{
    if (len == 0)
        return 1;
    if (port[0] != ':' || len == 1 || len > 6)
        return 0;
    for (size_t i = 1; i < len; i++)
        if (port[i] < '0' || port[i] > '9')
            return 0;
    return 1;
}

int http_host_served(const char *host, const char *allow)
{
    char addr[INET6_ADDRSTRLEN + 1];
    unsigned char bin[sizeof(struct in6_addr)];
    size_t len = strlen(host), name;

    if (allow && strcmp(allow, "*") == 0)
        return 1;
    if (host[0] == '[') { /* an IPv6 literal, with or without a port */
        const char *close = strchr(host, ']');
        name = close ? (size_t)(close - host) + 1 : 0;
        if (!close || name - 2 >= sizeof addr || !port_ok(close + 1, strlen(close + 1)))
            return 0;
        memcpy(addr, host + 1, name - 2);
        addr[name - 2] = '\0';
        return inet_pton(AF_INET6, addr, bin) == 1;
    }
    name = strcspn(host, ":");
    if (name == 0 || !port_ok(host + name, len - name))
        return 0;
    if (name < sizeof addr) { /* an IPv4 literal: no name that DNS could answer */
        memcpy(addr, host, name);
        addr[name] = '\0';
        if (inet_pton(AF_INET, addr, bin) == 1)
            return 1;
    }
    return (name == 9 && strncasecmp(host, "localhost", 9) == 0) || listed(allow, host, name) ||
           listed(allow, host, len);
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
