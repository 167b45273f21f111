/* Temporary: replaced by the OpenImageIO-backed implementation. */
#include "img.h"

int img_write_exr_named(const char *path, int width, int height, int nch,
                        const char *const *names, const float *data,
                        glint_err *err)
{
    return glint_err_set(err, GLINT_EUNSUPPORTED, "image I/O not built yet");
}
