/* log.c: diagnostic lines (log.h). */
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "log.h"

static int is_hex(char c)
{
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

void log_clean(const char *in, char *out, size_t len)
{
    size_t o = 0;
    if (!len)
        return;
    for (size_t i = 0; in[i] && o + 5 < len;) {
        size_t run = 0;
        while (is_hex(in[i + run]))
            run++;
        if (run >= 32) {
            memcpy(out + o, "{id}", 4);
            o += 4;
            i += run;
            continue;
        }
        if (run) { /* a short hex run: as is */
            for (size_t k = 0; k < run && o + 5 < len; k++)
                out[o++] = in[i + k];
            i += run;
            continue;
        }
        {
            unsigned char c = (unsigned char)in[i++];
            if (c < 0x20 || c >= 0x7f || c == '\\')
                o += (size_t)snprintf(out + o, len - o, "\\x%02x", c);
            else
                out[o++] = (char)c;
        }
    }
    out[o] = '\0';
}

void log_line(const char *fmt, ...)
{
    char raw[2048], clean[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    log_clean(raw, clean, sizeof clean);
    fprintf(stderr, "glintd: %s\n", clean);
}

#define PRIVATE_MAX 4
static char private_paths[PRIVATE_MAX][4096];
static int nprivate;

void log_private_path(const char *path)
{
    if (path && *path && nprivate < PRIVATE_MAX && strlen(path) < sizeof private_paths[0])
        snprintf(private_paths[nprivate++], sizeof private_paths[0], "%s", path);
}

void log_redact_paths(char *msg, size_t len)
{
    static const char repl[] = "<data>";
    for (int i = 0; i < nprivate; i++) {
        size_t pl = strlen(private_paths[i]);
        char *at;
        while ((at = strstr(msg, private_paths[i]))) {
            size_t tail = strlen(at + pl);
            if ((size_t)(at - msg) + sizeof repl - 1 + tail + 1 > len)
                break;
            memmove(at + sizeof repl - 1, at + pl, tail + 1);
            memcpy(at, repl, sizeof repl - 1);
        }
    }
}
