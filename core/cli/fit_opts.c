/* fit_opts.c: the fit options of the command line (fit, fit-samples,
 * demo), read from the methods' own parameter tables (method.h): --method
 * NAME picks the method (default: the first registered), --NAME VALUE
 * sets one of its parameters with the same checks and bounds as the API,
 * --cache-dir DIR / --no-cache choose the precomputation cache on disk. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#define FIT_OPT_BASE 2000

const char *default_cache_dir(void)
{
    static char buf[4096];
    const char *x = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    if (x && *x)
        snprintf(buf, sizeof buf, "%s/glint", x);
    else if (home && *home)
        snprintf(buf, sizeof buf, "%s/.cache/glint", home);
    else
        return NULL;
    return buf;
}

/* Every parameter spelling of every method, once (OUT: names, count). */
static int param_names(const char **names, int max)
{
    int n = 0;
    for (int i = 0; i < method_count(); i++) {
        const method *m = method_at(i);
        for (int k = 0; k < m->nparams; k++) {
            const char *sp[2] = {m->params[k].name, m->params[k].option};
            for (int s = 0; s < 2; s++) {
                int dup = 0;
                if (!sp[s])
                    continue;
                for (int j = 0; j < n; j++)
                    dup |= strcmp(names[j], sp[s]) == 0;
                if (!dup && n < max)
                    names[n++] = sp[s];
            }
        }
    }
    return n;
}

struct option *fit_opts_table(const struct option *own, int nown)
{
    const char *names[128];
    int np = param_names(names, 128), n = 0;
    struct option *t = calloc((size_t)(nown + np + 4), sizeof *t);
    if (!t)
        return NULL;
    for (int i = 0; i < nown; i++)
        t[n++] = own[i];
    t[n++] = (struct option){"method", required_argument, 0, FIT_OPT_BASE - 1};
    t[n++] = (struct option){"cache-dir", required_argument, 0, FIT_OPT_BASE - 2};
    t[n++] = (struct option){"no-cache", no_argument, 0, FIT_OPT_BASE - 3};
    for (int i = 0; i < np; i++)
        t[n++] = (struct option){names[i], required_argument, 0, FIT_OPT_BASE + i};
    return t; /* zeroed terminator */
}

void fit_opts_init(fit_opts *o)
{
    memset(o, 0, sizeof *o);
    o->cache_dir = default_cache_dir();
}

int fit_opt(fit_opts *o, int c, const char *arg)
{
    const char *names[128];
    int np;
    if (c == FIT_OPT_BASE - 1) {
        o->method_name = arg;
        return 0;
    }
    if (c == FIT_OPT_BASE - 2) {
        o->cache_dir = arg;
        return 0;
    }
    if (c == FIT_OPT_BASE - 3) {
        o->cache_dir = NULL;
        return 0;
    }
    np = param_names(names, 128);
    if (c < FIT_OPT_BASE || c >= FIT_OPT_BASE + np)
        return GLINT_ENOTFOUND;
    if (o->nset == FIT_OPTS_MAX)
        return fail(1, "too many fit options");
    o->set[o->nset].name = names[c - FIT_OPT_BASE];
    o->set[o->nset].value = arg;
    o->nset++;
    return 0;
}

int fit_opts_resolve(fit_opts *o)
{
    glint_err e;
    char list[256];

    o->m = o->method_name ? method_find(o->method_name) : method_at(0);
    if (!o->m) {
        method_names(list, sizeof list);
        return fail(1, "--method '%s': not a method (available: %s)", o->method_name, list);
    }
    if (!(o->params = method_params_new(o->m)))
        return fail(1, "out of memory");
    for (int i = 0; i < o->nset; i++)
        if (method_param_set_text(o->m, o->params, o->set[i].name, o->set[i].value, &e))
            return fail_err(&e);
    if (o->m->params_check && o->m->params_check(o->params, &e))
        return fail_err(&e);
    return 0;
}

void fit_opts_free(fit_opts *o)
{
    free(o->params);
    o->params = NULL;
}

void fit_opts_usage(FILE *f)
{
    fputs("fit options:\n"
          "  --method NAME      the fit method (glint methods lists them; default: the first)\n"
          "  --cache-dir DIR    precomputation cache on disk ($XDG_CACHE_HOME/glint); --no-cache\n",
          f);
    for (int i = 0; i < method_count(); i++) {
        const method *m = method_at(i);
        void *def = method_params_new(m);
        fprintf(f, "  parameters of %s (%s):\n", m->name, m->title);
        for (int k = 0; def && k < m->nparams; k++) {
            const method_param *p = &m->params[k];
            char v[256], opt[64];
            method_param_format(p, def, v, sizeof v);
            snprintf(opt, sizeof opt, "--%s", p->option ? p->option : p->name);
            fprintf(f, "    %-16s %s (%s)\n", opt, p->description, v);
        }
        free(def);
    }
}
