/* dtoa.cpp: the shortest decimal text that reads back as the same double,
 * by {fmt} (Debian's libfmt: Dragonbox), for json_text.c.  extern "C"; no
 * exception leaves it. */
#include <fmt/compile.h>
#include <fmt/format.h>
#include <string.h>

#include "err.h"
#include "json_text.h"

extern "C" int glint_dtoa_shortest(double v, char *buf, int size)
{
    char tmp[64]; /* the longest text is 24 bytes ("-2.2250738585072014e-308") */
    size_t n;
    if (!(v - v == 0.0)) /* inf or NaN */
        return GLINT_ENONFINITE;
    try {
        n = (size_t)(fmt::format_to(tmp, FMT_COMPILE("{}"), v) - tmp);
    } catch (...) {
        return GLINT_EINTERNAL;
    }
    if (!memchr(tmp, '.', n) && !memchr(tmp, 'e', n)) {
        /* "1" -> "1.0": it reads back as a real, as jansson's text does */
        tmp[n++] = '.';
        tmp[n++] = '0';
    }
    if (n + 1 > (size_t)(size > 0 ? size : 0))
        return GLINT_ERANGE;
    memcpy(buf, tmp, n);
    buf[n] = '\0';
    return (int)n;
}
