/* method_small.h: small parameters for each built-in method, for tests that
 * run every method's whole path many times (test_alloc_fail.c,
 * test_method_sweep.c): the paths are the same at any size. */
#ifndef GLINT_METHOD_SMALL_H
#define GLINT_METHOD_SMALL_H

#include <stdio.h>
#include <string.h>

#include "method.h"

static const char *const method_small[][2] = {
    {"hf3", "res=8"},
    {"pbr", "starts=1,max_iter=20"},
    {"pbr_detail", "res=8,starts=1,max_iter=20"},
    {"tab", "res_h=8,res_d=4"},
    {"pbr_tab", "res_h=8,res_d=4,starts=1"},
    {"pbr_maps", "starts=1,components=2,map_res=16,rounds=2"},
    {"srbf", "lights=8,basis_res=2,raster=full,grazing=0"},
    {"pbr_env", "lights=8,starts=1,max_iter=20,raster=full"},
    {"pbr_tab_env", "lights=8,starts=1,raster=full,res_h=8,res_d=4"},
    {"hf4", "res=8,s_res=4"},
    {"hf2d", "res=8,res_2d=8"},
    {"maps", "res=8,components=2,map_res=16,rounds=2"},
    {"hybrid", "res=8,s_res=4,components=2,map_res=16,rounds=2"},
    {"auto", "res=8,s_res=4,res_2d=8,components=2"},
    {"auto_env", "lights=8"},
};
#define METHOD_SMALL_N ((int)(sizeof method_small / sizeof *method_small))

/* Set "name=value,..." on params of m; 0 or the first error. */
static inline int method_small_set(const method *m, void *params, const char *spec,
                                   glint_err *e)
{
    char buf[256], *tok, *save;
    snprintf(buf, sizeof buf, "%s", spec);
    for (tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(tok, '=');
        int rc;
        if (!eq)
            return glint_err_set(e, GLINT_EINVAL, "'%s' is not name=value", tok);
        *eq = '\0';
        if ((rc = method_param_set_text(m, params, tok, eq + 1, e)))
            return rc;
    }
    return 0;
}

#endif
