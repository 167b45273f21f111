/* fuzz_image.c: image bytes from outside, decoded as glintd decodes an
 * upload.  The first byte picks the reader, the rest is the file:
 *   0  a painting or photo (PUT .../paintings/K, the photo bar):
 *      img_read_mem_max, through the OpenImageIO shim;
 *   1  an environment map (POST /environments): env_load_mem, lat-long or
 *      cube cross, then its texels must be finite and non-negative;
 *   2  a MERL table (glintd --measured-dir, paint --brdf merl:FILE):
 *      merl_read_mem, then every entry must be finite.
 * What decodes must keep to the size limit it was given. */
#include <math.h>

#include "env.h"
#include "fuzz.h"
#include "img.h"
#include "merl.h"

#define MAX_DIM 512

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    glint_err e;
    if (size < 1 || size > (size_t)64 << 20)
        return 0;
    switch (data[0] % 3) {
    case 0: {
        img im = {0};
        if (img_read_mem_max(data + 1, size - 1, MAX_DIM, &im, &e) == 0) {
            FUZZ_CHECK(im.width >= 1 && im.width <= MAX_DIM && im.height >= 1 &&
                       im.height <= MAX_DIM && im.channels >= 1 && im.channels <= 4);
            FUZZ_CHECK(im.px != NULL);
            img_free(&im);
        } else {
            FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("image", e.msg);
        }
        break;
    }
    case 1: {
        env_map m = {0};
        if (env_load_mem(data + 1, size - 1, "upload", MAX_DIM, &m, &e) == 0) {
            size_t n = (size_t)m.width * m.height * 3;
            FUZZ_CHECK(m.width == 2 * m.height && m.height >= 1);
            for (size_t i = 0; i < n; i++)
                FUZZ_CHECK(isfinite(m.rgb[i]) && m.rgb[i] >= 0);
            env_map_free(&m);
        } else {
            FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("image", e.msg);
        }
        break;
    }
    default: {
        merl_table t = {0};
        if (merl_read_mem(data + 1, size - 1, &t, &e) == 0)
            merl_free(&t);
        else
            FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("image", e.msg);
        break;
    }
    }
    return 0;
}
