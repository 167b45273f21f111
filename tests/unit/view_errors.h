/* view_errors.h: the check of a fit's errors by view (errors.rms_by_view,
 * method_rms_by_view) shared by the tests of the methods that give them. */
#ifndef GLINT_TEST_VIEW_ERRORS_H
#define GLINT_TEST_VIEW_ERRORS_H

#include <jansson.h>
#include <math.h>

/* NULL when info's errors.rms_by_view is as method.h says: entries in
 * ascending view order, samples adding up to precomputation.samples, and
 * sqrt(sum(samples rms^2) / sum(samples)) rms_painted within 1e-9 relative;
 * else what is wrong. */
static const char *rms_by_view_wrong(const json_t *info)
{
    const json_t *errs = json_object_get(info, "errors");
    const json_t *a = json_object_get(errs, "rms_by_view");
    double rms = json_number_value(json_object_get(errs, "rms_painted")), ss = 0.0;
    long total = (long)json_integer_value(
             json_object_get(json_object_get(info, "precomputation"), "samples")),
         n = 0;
    int last = -1;

    if (!json_is_array(a) || json_array_size(a) == 0)
        return "errors.rms_by_view missing or empty";
    for (size_t i = 0; i < json_array_size(a); i++) {
        const json_t *e = json_array_get(a, i);
        int v = (int)json_integer_value(json_object_get(e, "view"));
        long k = (long)json_integer_value(json_object_get(e, "samples"));
        double r = json_number_value(json_object_get(e, "rms"));
        if (v <= last || k < 1 || !(r >= 0.0))
            return "an entry of errors.rms_by_view out of order or empty";
        last = v;
        n += k;
        ss += k * r * r;
    }
    if (n != total)
        return "the samples of errors.rms_by_view do not add up to the samples";
    if (!(fabs(sqrt(ss / n) - rms) <= 1e-9 * rms))
        return "errors.rms_by_view does not make rms_painted";
    return NULL;
}

#endif
