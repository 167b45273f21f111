/* hf_map.c: mappings between linear and log space (section 3.4). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf.h"

void hf_map_default(hf_map *m, hf_map_kind kind)
{
    m->kind = kind;
    m->a = 0.1;
    m->eps = 1e-3;
    m->margin = 0.01;
}

static int parse_num(const char *p, const char *what, double lo, double hi,
                     double *out, glint_err *err)
{
    char *end;
    double v = strtod(p, &end);
    if (end == p || *end || !isfinite(v) || v < lo || v > hi)
        return glint_err_set(err, GLINT_EINVAL, "%s '%s' must be a number in [%g, %g]",
                             what, p, lo, hi);
    *out = v;
    return 0;
}

int hf_map_parse(const char *spec, hf_map *out, glint_err *err)
{
    char buf[128], *eps, *colon;
    int rc;

    if (!spec || strlen(spec) >= sizeof buf)
        return glint_err_set(err, GLINT_EINVAL, "missing or overlong mapping");
    strcpy(buf, spec);
    eps = strstr(buf, ",eps=");
    if (eps)
        *eps = '\0';
    colon = strchr(buf, ':');
    if (colon)
        *colon = '\0';
    if (strcmp(buf, "log") == 0)
        hf_map_default(out, HF_MAP_LOG);
    else if (strcmp(buf, "add") == 0)
        hf_map_default(out, HF_MAP_ADD);
    else if (strcmp(buf, "sub") == 0)
        hf_map_default(out, HF_MAP_SUB);
    else
        return glint_err_set(err, GLINT_EINVAL, "unknown mapping '%s' (log, add[:a], sub[:margin])",
                             spec);
    if (colon) {
        if (out->kind == HF_MAP_ADD)
            rc = parse_num(colon + 1, "add offset a", 1e-6, 1e6, &out->a, err);
        else if (out->kind == HF_MAP_SUB)
            rc = parse_num(colon + 1, "sub margin", 1e-6, 10.0, &out->margin, err);
        else
            rc = glint_err_set(err, GLINT_EINVAL, "mapping 'log' takes no parameter");
        if (rc)
            return rc;
    }
    if (eps)
        return parse_num(eps + 5, "eps", 1e-12, 1.0, &out->eps, err);
    return 0;
}

void hf_map_format(const hf_map *m, char *buf, size_t len)
{
    switch (m->kind) {
    case HF_MAP_ADD: snprintf(buf, len, "add:%g,eps=%g", m->a, m->eps); break;
    case HF_MAP_SUB: snprintf(buf, len, "sub:%g,eps=%g", m->margin, m->eps); break;
    default: snprintf(buf, len, "log,eps=%g", m->eps); break;
    }
}

double hf_map_offset(const hf_map *m, double vmax)
{
    if (m->kind == HF_MAP_ADD)
        return m->a;
    if (m->kind == HF_MAP_SUB)
        return vmax > 0.0 ? fmin((1.0 + m->margin) * vmax, FLT_MAX) : 1.0;
    return 0.0;
}

double hf_map_arg(const hf_map *m, double a, double v)
{
    switch (m->kind) {
    case HF_MAP_ADD: return a + v;
    case HF_MAP_SUB: return a - v;
    default: return v;
    }
}

double hf_map_inverse(const hf_map *m, double a, double prod)
{
    double v;
    switch (m->kind) {
    case HF_MAP_ADD: v = prod - a; break;
    case HF_MAP_SUB: v = a - prod; break;
    default: v = prod; break;
    }
    return v > 0.0 ? v : 0.0;
}
