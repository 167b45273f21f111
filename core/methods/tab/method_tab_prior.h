/* method_tab_prior.h: the tab_prior method: tab's table (method_tab.h)
 * continued along theta_d beyond the painted rows, as a prior learned from
 * measured materials says such materials go on (tab_prior.h).
 *
 * The learning set is the host's measured fits file (glintd
 * --measured-dir, the command line's $GLINT_MEASURED_DIR): without one the
 * fit fails and says so.  params.exclude leaves materials out of it (a
 * benchmark's evaluation materials: "every/4" leaves out materials 0, 4,
 * 8, ... of the file, the ones `--every 4` evaluates).
 *
 * Levels (each in the cache under its own key): tab's tab-design and
 * tab-operator (shared with tab: the same keys), then
 *   tab-prior     the learned prior (params learn, exclude, components;
 *                 memory only: learning takes a few tens of ms)
 *
 * The material is a tab material (its manifest is tab's); its info is
 * tab's plus "prior": {"learned_from" (materials), "fit" (sgd or abc),
 * "components", "explained" (the fraction of the learning tables' variance
 * the components hold), "observed" (nodes the painting weighs on),
 * "coef_norm" and "changed" per channel (tab_prior_report)}.
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_TAB_PRIOR_H
#define GLINT_METHOD_TAB_PRIOR_H

#include "method_tab.h"
#include "tab_prior.h"

extern const method method_tab_prior;

#define TAB_PRIOR_EXCLUDE_MAX 1024 /* bytes of params.exclude, with its terminator */

typedef struct tab_prior_params {
    tab_params tab;                         /* first: tab's levels read it */
    int learn;                              /* measured_model: 0 abc, 1 sgd */
    char exclude[TAB_PRIOR_EXCLUDE_MAX];    /* "", "every/N" or NAME[+NAME...] */
    int components;
    double noise;                           /* the prediction's */
    double painted;                         /* tab_prior_opts.painted */
} tab_prior_params;

/* params.exclude's syntax (method_param's parse and format). */
int tab_prior_exclude_parse(const char *text, void *field, glint_err *err);
void tab_prior_exclude_format(const void *field, char *buf, size_t len);

/* The tab-prior level (method_level's key and build; its data a tab_prior,
 * learned from the process's fits file: GLINT_ENOTFOUND without one). */
void tab_prior_level_key(const void *p, const samples *s, const char *prev, char *key,
                         size_t len);
int tab_prior_level_build(const method_build_in *in, cache_value *out, glint_err *err);

#endif
