/* zip.c: stored zip archives with aligned data (zip.h). */
#include "zip.h"

#include <libdeflate.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LOCAL_HEADER 30
#define CENTRAL_HEADER 46
#define END_RECORD 22
#define PAD_ID 0x1986 /* a private extra-field id for the padding (as OpenUSD's USDZ writer pads) */

static void put16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)(v & 0xff);
    p[1] = (unsigned char)((v >> 8) & 0xff);
}

static void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)((v >> (8 * i)) & 0xff);
}

static int path_ok(const char *p)
{
    size_t n = p ? strlen(p) : 0;
    if (n == 0 || n > 255 || p[0] == '/' || strstr(p, "..") || strchr(p, '\\'))
        return 0;
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)p[i] < 32 || (unsigned char)p[i] > 126)
            return 0;
    return 1;
}

/* The padding a local header needs so that its data starts aligned: the
 * extra field (4 bytes of id and size, then zeros), 0 when none is needed. */
static size_t pad_for(size_t header_at, size_t name_len)
{
    size_t data_at = header_at + LOCAL_HEADER + name_len, pad;
    if (data_at % ZIP_ALIGN == 0)
        return 0;
    pad = ZIP_ALIGN - data_at % ZIP_ALIGN;
    return pad < 4 ? pad + ZIP_ALIGN : pad; /* room for the field's own 4 bytes */
}

int zip_pack(const zip_entry *files, int n, void **out, size_t *len, glint_err *err)
{
    size_t total = 0, central = 0, at = 0, cd_at;
    uint32_t crc[ZIP_MAX_FILES];
    size_t offset[ZIP_MAX_FILES], pad[ZIP_MAX_FILES];
    unsigned char *b;

    *out = NULL;
    *len = 0;
    if (n < 1 || n > ZIP_MAX_FILES)
        return glint_err_set(err, GLINT_ERANGE, "a package of %d files (1..%d)", n,
                             ZIP_MAX_FILES);
    for (int i = 0; i < n; i++) {
        size_t nl;
        if (!path_ok(files[i].path) || (!files[i].data && files[i].len))
            return glint_err_set(err, GLINT_EINVAL, "package file %d: a bad path or no data", i);
        nl = strlen(files[i].path);
        pad[i] = pad_for(total, nl);
        offset[i] = total;
        total += LOCAL_HEADER + nl + pad[i] + files[i].len;
        central += CENTRAL_HEADER + nl;
        if (total > UINT32_MAX || files[i].len > UINT32_MAX)
            return glint_err_set(err, GLINT_ERANGE, "a package over 4 GiB (no ZIP64)");
    }
    cd_at = total;
    total += central + END_RECORD;
    if (total > UINT32_MAX)
        return glint_err_set(err, GLINT_ERANGE, "a package over 4 GiB (no ZIP64)");
    if (!(b = calloc(1, total)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %zu-byte package", total);
    for (int i = 0; i < n; i++) {
        size_t nl = strlen(files[i].path);
        unsigned char *h = b + at;
        crc[i] = (uint32_t)libdeflate_crc32(0, files[i].data, files[i].len);
        put32(h, 0x04034b50);
        put16(h + 4, 20);                     /* version needed: 2.0 */
        put16(h + 6, 0);                      /* flags */
        put16(h + 8, 0);                      /* stored */
        put16(h + 10, 0);                     /* time 00:00 */
        put16(h + 12, (0 << 9) | (1 << 5) | 1); /* 1980-01-01 */
        put32(h + 14, crc[i]);
        put32(h + 18, (uint32_t)files[i].len);
        put32(h + 22, (uint32_t)files[i].len);
        put16(h + 26, (unsigned)nl);
        put16(h + 28, (unsigned)pad[i]);
        memcpy(h + LOCAL_HEADER, files[i].path, nl);
        if (pad[i]) {
            put16(h + LOCAL_HEADER + nl, PAD_ID);
            put16(h + LOCAL_HEADER + nl + 2, (unsigned)(pad[i] - 4));
        }
        at += LOCAL_HEADER + nl + pad[i];
        if (files[i].len)
            memcpy(b + at, files[i].data, files[i].len);
        at += files[i].len;
    }
    for (int i = 0; i < n; i++) {
        size_t nl = strlen(files[i].path);
        unsigned char *h = b + at;
        put32(h, 0x02014b50);
        put16(h + 4, 20);  /* made by: MS-DOS attributes, 2.0 */
        put16(h + 6, 20);
        put16(h + 8, 0);
        put16(h + 10, 0);
        put16(h + 12, 0);
        put16(h + 14, (0 << 9) | (1 << 5) | 1);
        put32(h + 16, crc[i]);
        put32(h + 20, (uint32_t)files[i].len);
        put32(h + 24, (uint32_t)files[i].len);
        put16(h + 28, (unsigned)nl);
        put16(h + 30, 0);  /* no extra field here */
        put16(h + 32, 0);  /* no comment */
        put16(h + 34, 0);  /* disk 0 */
        put16(h + 36, 0);
        put32(h + 38, 0);
        put32(h + 42, (uint32_t)offset[i]);
        memcpy(h + CENTRAL_HEADER, files[i].path, nl);
        at += CENTRAL_HEADER + nl;
    }
    put32(b + at, 0x06054b50);
    put16(b + at + 8, (unsigned)n);
    put16(b + at + 10, (unsigned)n);
    put32(b + at + 12, (uint32_t)central);
    put32(b + at + 16, (uint32_t)cd_at);
    *out = b;
    *len = total;
    return 0;
}
