/* zip.h: several files as one stored zip archive, the container of the
 * USDZ (usdz.h) and MaterialX (mtlx.h) packages.
 *
 * The format (PKWARE's APPNOTE.TXT, the subset every zip reader takes):
 * local file headers, the data stored (not compressed nor encrypted), the
 * central directory and its end record; no ZIP64 (at most ZIP_MAX_FILES
 * files and 4 GiB, refused beyond).  Each file's data starts at a multiple
 * of ZIP_ALIGN bytes from the start of the archive (the local header's
 * extra field pads to it), as OpenUSD's "Usdz File Format Specification"
 * requires and any other reader ignores.  CRC-32 by libdeflate; times set
 * to 1980-01-01 so that an archive is a function of its files.  Paths are
 * relative, '/'-separated, printable ASCII, no "..", at most 255 bytes.
 *
 * Thread-safety: no state. */
#ifndef GLINT_ZIP_H
#define GLINT_ZIP_H

#include <stddef.h>

#include "err.h"

#define ZIP_ALIGN 64
#define ZIP_MAX_FILES 64

typedef struct zip_entry {
    const char *path;
    const void *data;
    size_t len;
} zip_entry;

/* The archive of files[0..n-1] in that order.  OUT: *out (malloc'ed: the
 * caller frees), *len.  GLINT_EINVAL for a bad path or data missing,
 * GLINT_ERANGE for n outside 1..ZIP_MAX_FILES or over 4 GiB, GLINT_ENOMEM. */
int zip_pack(const zip_entry *files, int n, void **out, size_t *len, glint_err *err);

#endif
