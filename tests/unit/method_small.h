/* method_small.h: small parameters for each built-in method, for tests that
 * run every method's whole path many times (test_alloc_fail.c,
 * test_method_sweep.c): the paths are the same at any size. */
#ifndef GLINT_METHOD_SMALL_H
#define GLINT_METHOD_SMALL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "measured.h"
#include "method.h"

static const char *const method_small[][2] = {
    {"hf3", "res=8"},
    {"pbr", "starts=1,max_iter=20"},
    {"pbr_detail", "res=8,starts=1,max_iter=20"},
    {"tab", "res_h=8,res_d=4"},
    {"tab_prior", "res_h=8,res_d=4,components=2"},
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

/* The measured fits the methods that learn from them read (tab_prior): a
 * file of three materials written to /tmp (removed at exit) and set as the
 * process's.  0, or -1 when it cannot be written. */
static char method_small_fits_[64];

static inline void method_small_fits_remove_(void)
{
    unlink(method_small_fits_);
}

static inline int method_small_measured(void)
{
    static const char doc[] =
        "{\"materials\": [" 
        "{\"name\": \"a\", \"abc\": {\"kD\": [0.1, 0.1, 0.1], \"A\": [1, 1, 1], \"B\": 10, "
        "\"C\": 1, \"ior\": 1.5}, \"sgd\": {\"rhoD\": [0.1, 0.1, 0.1], \"rhoS\": [0.5, 0.5, 0.5], "
        "\"alpha\": [0.02, 0.02, 0.02], \"p\": [0.5, 0.5, 0.5], \"f0\": [0.04, 0.04, 0.04], "
        "\"f1\": [0, 0, 0], \"kap\": [0.3, 0.3, 0.3], \"lambda\": [0, 0, 0], \"c\": [1, 1, 1], "
        "\"k\": [1, 1, 1], \"theta0\": [0, 0, 0]}},"
        "{\"name\": \"b\", \"abc\": {\"kD\": [0.3, 0.3, 0.3], \"A\": [1, 1, 1], \"B\": 10, "
        "\"C\": 1, \"ior\": 1.5}, \"sgd\": {\"rhoD\": [0.3, 0.2, 0.1], \"rhoS\": [0.2, 0.2, 0.2], "
        "\"alpha\": [0.05, 0.05, 0.05], \"p\": [0.5, 0.5, 0.5], \"f0\": [0.04, 0.04, 0.04], "
        "\"f1\": [0, 0, 0], \"kap\": [0.3, 0.3, 0.3], \"lambda\": [0, 0, 0], \"c\": [1, 1, 1], "
        "\"k\": [1, 1, 1], \"theta0\": [0, 0, 0]}},"
        "{\"name\": \"c\", \"abc\": {\"kD\": [0.5, 0.5, 0.5], \"A\": [1, 1, 1], \"B\": 10, "
        "\"C\": 1, \"ior\": 1.5}, \"sgd\": {\"rhoD\": [0.5, 0.4, 0.3], \"rhoS\": [0.1, 0.1, 0.1], "
        "\"alpha\": [0.1, 0.1, 0.1], \"p\": [0.5, 0.5, 0.5], \"f0\": [0.04, 0.04, 0.04], "
        "\"f1\": [0, 0, 0], \"kap\": [0.3, 0.3, 0.3], \"lambda\": [0, 0, 0], \"c\": [1, 1, 1], "
        "\"k\": [1, 1, 1], \"theta0\": [0, 0, 0]}}]}";
    FILE *f;
    if (method_small_fits_[0])
        return 0;
    snprintf(method_small_fits_, sizeof method_small_fits_, "/tmp/glint-small-fits-%d.json",
             (int)getpid());
    if (!(f = fopen(method_small_fits_, "w")))
        return -1;
    fputs(doc, f);
    fclose(f);
    atexit(method_small_fits_remove_);
    measured_set_file(method_small_fits_, NULL);
    return 0;
}

#endif
