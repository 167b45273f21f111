/* fuzz_config.c: glintd's config file (--config FILE): config_load_text
 * over the defaults.  Whatever loads keeps every setting in the range its
 * option allows and every path NUL-terminated within its field. */
#include <string.h>

#include "config.h"
#include "fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    app_config c;
    glint_err e;
    if (size > CONFIG_MAX_FILE)
        return 0;
    config_default(&c);
    if (config_load_text(&c, (const char *)data, size, "fuzz", &e)) {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("config", e.msg);
        return 0;
    }
    FUZZ_CHECK(c.port >= 0 && c.port <= 65535);
    FUZZ_CHECK(c.worker_threads >= 1 && c.worker_threads <= 64);
    FUZZ_CHECK(c.work_slots >= 1 && c.lim.max_image_dim >= 8 && c.lim.max_strokes >= 1);
    FUZZ_CHECK(c.cache_bytes >= (size_t)1 << 20 && c.lim.max_body >= (size_t)1 << 20);
    FUZZ_CHECK(memchr(c.data_dir, 0, sizeof c.data_dir) && memchr(c.address, 0, sizeof c.address));
    FUZZ_CHECK(memchr(c.api_key, 0, sizeof c.api_key) &&
               memchr(c.allow_origin, 0, sizeof c.allow_origin));
    return 0;
}
