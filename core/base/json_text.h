/* json_text.h: JSON text of a jansson tree, its reals in the shortest
 * decimal form that reads back as the same double.
 *
 * json_dumps with JSON_REAL_PRECISION(17) prints every real with glibc's
 * exact "%.17g", about 0.4-0.5 us a real here: a material's manifest
 * (about 620 reals, 20 KB) took 0.4-0.9 ms of a fit's save.  json_text
 * prints them in {fmt}'s shortest form instead (Dragonbox, dtoa.cpp):
 * the same doubles when read back (json_loads, strtod), in as few digits
 * as that takes (0.1 is "0.1", 1e21 "1e+21", 1.0 "1.0").
 *
 * The layout is json_dumps's, byte for byte apart from the reals: indent
 * 0 is JSON_COMPACT, indent n > 0 is JSON_INDENT(n); objects' keys in
 * their order in the object; strings escaped as json_dumps escapes them
 * (no JSON_ENSURE_ASCII, no JSON_ESCAPE_SLASH).  A real is printed with a
 * "." or an exponent, so that it reads back as a real.  Returns a
 * malloc'ed string, or NULL when out of memory, for a tree deeper than
 * JSON_TEXT_MAX_DEPTH (or a cycle), or indent outside 0..31.  The depth
 * is twice what jansson's parser takes (2048), so a parsed document fits
 * inside any response that wraps it. */
#ifndef GLINT_JSON_TEXT_H
#define GLINT_JSON_TEXT_H

#ifdef __cplusplus
extern "C" {
#endif

#define JSON_TEXT_MAX_DEPTH 4096

#ifndef __cplusplus
#include <jansson.h>
char *json_text(const json_t *j, int indent);
#endif

/* The shortest text of a finite v that reads back as v, with a "." or an
 * exponent, into buf (NUL-terminated; 32 bytes are enough), its length;
 * GLINT_ERANGE when it does not fit, GLINT_ENONFINITE when v is not finite. */
int glint_dtoa_shortest(double v, char *buf, int size);

#ifdef __cplusplus
}
#endif

#endif
