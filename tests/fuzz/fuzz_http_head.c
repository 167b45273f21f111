/* fuzz_http_head.c: the request head as glintd's front reads it off the
 * socket, before libmicrohttpd (http_head_parse), and the request target
 * as the log writes it (http_head_log_target).  A head that parses lies
 * inside the bytes given, within the limits; a refused one names a 4xx or
 * 505 status; a log line is one line of printable ASCII. */
#include <string.h>

#include "fuzz.h"
#include "http_head.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *buf = (const char *)data;
    http_head_limits lim = {8192, 2048, 64, (uint64_t)32 << 20};
    http_head h;
    http_head_error he;
    char line[256];
    int rc;

    if (size > 1 << 16)
        return 0;
    memset(&he, 0, sizeof he);
    rc = http_head_parse(buf, size, &lim, &h, &he);
    if (rc == HTTP_HEAD_OK) {
        FUZZ_CHECK(h.len <= size && h.len <= lim.max_head);
        FUZZ_CHECK(h.method_off + h.method_len <= h.len && h.target_off + h.target_len <= h.len);
        FUZZ_CHECK(h.target_len <= lim.max_target && h.content_length >= -1);
        http_head_log_target(buf + h.target_off, h.target_len, line, sizeof line);
    } else if (rc == HTTP_HEAD_BAD) {
        FUZZ_CHECK((he.status >= 400 && he.status < 500) || he.status == 505);
        FUZZ_CHECK(he.slug != NULL && memchr(he.detail, 0, sizeof he.detail) != NULL);
    } else {
        FUZZ_CHECK(rc == HTTP_HEAD_MORE);
    }
    /* any bytes, as a target */
    http_head_log_target(buf, size, line, sizeof line);
    FUZZ_CHECK(memchr(line, 0, sizeof line) != NULL);
    for (const char *p = line; *p; p++)
        FUZZ_CHECK(*p >= 0x20 && *p <= 0x7e);
    return 0;
}
