/* upload_gate.h: the check every uploaded image passes before a pixel of
 * it is decoded.
 *
 * An image's size and channels are in its header, and its decode takes
 * memory by them, not by the bytes sent: a 764 KB PNG may declare 16384 x
 * 16384 (3 GiB of floats).  So every upload is decoded through a core
 * reader that shows the header first (img_read_mem_checked; gbfit_gbuf_mem
 * and env_load_mem pass it on) with upload_gate_check, which, in order:
 *   - refuses a side beyond max_dim (413 image-too-large naming the limit,
 *     or the caller's too_large_code and kind);
 *   - refuses a size the target does not take (422 wrong-size: "the
 *     painting is 16384x16384; view 0 of this scene expects exactly 32x32");
 *   - refuses more channels than max_channels (422, the caller's
 *     invalid_kind);
 *   - admits the decode's bound (img_header.decode_bytes) plus per_pixel
 *     bytes per pixel of the caller's work on the image against the work
 *     budget (admit_enter: 413 over-budget, 503 busy).
 * The memory of an upload's decode is thus held in the budget before it is
 * taken, for the direct PNG path and OpenImageIO's formats alike.  After
 * the read (whatever it returned) the caller gives the bytes back with
 * upload_gate_leave.
 *
 * A gate lives on the caller's stack for one read; not shared. */
#ifndef GLINTD_UPLOAD_GATE_H
#define GLINTD_UPLOAD_GATE_H

#include <stddef.h>

#include "app.h"
#include "err.h"
#include "img.h"

typedef struct upload_gate {
    app *a;
    const char *what;   /* names the upload in messages: "the painting" */
    int nsizes;         /* sizes taken, w[i] x h[i]; 0: any within max_dim */
    int w[2], h[2];
    char expect[200];   /* what the target takes, for messages ("" when any) */
    int max_dim;        /* a side at most */
    const char *max_dim_name; /* the limit's name: "max_image_dim, glintd --max-image-dim" */
    int too_large_code;       /* for a side beyond max_dim: GLINT_ETOOBIG ... */
    const char *too_large_kind; /* ... "image-too-large" */
    int max_channels;
    const char *invalid_kind; /* for too many channels: "invalid-image" */
    size_t per_pixel;   /* bytes per pixel the caller's work on the image adds */
    /* set by the check */
    img_header hd;      /* the header, when seen */
    int seen;           /* 1 once upload_gate_check ran */
    int refused;        /* 1 when it refused: the error is the answer as it is */
    size_t held;        /* bytes admitted (upload_gate_leave) */
} upload_gate;

/* A gate for `what` (a static string) with max_dim = --max-image-dim
 * (413 image-too-large), channels up to 4, any size, nothing per pixel:
 * set the other fields, and add sizes with upload_gate_size. */
void upload_gate_init(upload_gate *g, app *a, const char *what);

/* Take images of w x h too (at most two sizes). */
void upload_gate_size(upload_gate *g, int w, int h);

/* img_header_check: cls is the upload_gate. */
int upload_gate_check(void *cls, const img_header *hd, glint_err *err);

/* Give back what the check admitted (none: nothing). */
void upload_gate_leave(upload_gate *g);

#endif
