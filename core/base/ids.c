/* ids.c: random ids and constant-time comparison (ids.h). */
#include "ids.h"

#include <errno.h>
#include <string.h>
#include <sys/random.h>

int glint_id_new(char id[GLINT_ID_LEN], glint_err *err)
{
    static const char hex[] = "0123456789abcdef";
    unsigned char b[16];
    size_t got = 0;

    while (got < sizeof b) {
        ssize_t n = getrandom(b + got, sizeof b - got, 0);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            id[0] = '\0';
            return glint_err_set(err, GLINT_EIO, "getrandom: %s", strerror(errno));
        }
        got += (size_t)n;
    }
    for (int i = 0; i < 16; i++) {
        id[2 * i] = hex[b[i] >> 4];
        id[2 * i + 1] = hex[b[i] & 15];
    }
    id[32] = '\0';
    return 0;
}

int glint_id_new_near(const char *near, char id[GLINT_ID_LEN], glint_err *err)
{
    int rc = glint_id_new(id, err);
    if (!rc && glint_id_valid(near))
        memcpy(id, near, GLINT_ID_ROUTE);
    return rc;
}

int glint_id_valid(const char *s)
{
    if (!s)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return 0;
    return s[32] == '\0';
}

int glint_secret_equal(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b), n = la > lb ? la : lb;
    unsigned char diff = (unsigned char)(la != lb);
    for (size_t i = 0; i < n; i++) {
        unsigned char ca = i < la ? (unsigned char)a[i] : 0;
        unsigned char cb = i < lb ? (unsigned char)b[i] : 0;
        diff |= (unsigned char)(ca ^ cb);
    }
    return diff == 0;
}
