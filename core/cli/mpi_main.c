/* glint-mpi: glint's precomputations distributed over MPI ranks, written
 * to the same cache files the command line and glintd read.
 *
 *   mpirun -np N glint-mpi decompose scene.json [--paintings DIR | --views LIST]
 *          [--cache-dir DIR] [--threads T] [--force] [--quiet] [hf3 options]
 *
 * decompose makes the decomposition of the pattern that
 * `glint fit scene.json --paintings DIR` (or glintd, for the same views)
 * uses, under the key that fit computes, so that the fit then loads it
 * from the cache instead of building it: hf3's (the default method;
 * hf_mpi.h; pcache_key_hf of the pattern hash and --res, --lambda,
 * --route, --rcond: a .hfd file), hf4's (--method hf4; hfx_mpi.h, its
 * normal form; hf4_level_key of the pattern hash and --res, --s_res,
 * --lambda, --lambda_s, --rcond: a .hf4 file) or hf2d's (--method hf2d;
 * the same normal form; hf2d_level_key: a .hf2d file).  The views: those with a painting
 * in DIR (view_KK.exr, ... as fit reads them), or the list given, or every
 * view.  Each rank rasterizes its share of the used views (the k-th used
 * view goes to rank k mod N) on T threads (default: this node's cores
 * shared among its ranks), builds the design of its own samples and its
 * share of the normal matrix; rank 0 writes the file and prints a JSON
 * report on stdout (timings, and per rank its samples and peak resident
 * memory).  Every rank must be able to read the scene file (and its
 * mesh) at the same path; only rank 0 writes.
 *
 * Messages and exit statuses are glint's (cli.h): 1 bad usage or invalid
 * input, 2 I/O error, 3 numerical failure.  Every rank reaches the same
 * decision; rank 0 alone prints, naming the rank where a step failed. */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <mpi.h>
#include <sys/resource.h>

#include "cli.h"
#include "cfile.h"
#include "hf_mpi.h"
#include "hfx_mpi.h"
#include "method_hf2d.h"
#include "method_hf3.h"
#include "method_hf4.h"
#include "pattern.h"
#include "pcache.h"
#include "samples.h"

#define GLINT_MPI_VERSION "0.1.0"

static int my_rank, nranks;

static const char usage_text[] =
    "usage: mpirun -np N glint-mpi decompose scene.json [--paintings DIR | --views LIST]\n"
    "         [--cache-dir DIR] [--threads T] [--force] [--quiet] [hf3 options]\n"
    "  The decomposition of the scene's pattern (--method hf3, the default, hf4 or hf2d),\n"
    "  distributed over the ranks, written to the cache directory under the key\n"
    "  `glint fit` looks up (same views, same method options).  Views: those with a\n"
    "  painting in DIR, or LIST (\"0,1,5\"), or all.  --force rebuilds a decomposition\n"
    "  already cached.  hf3: route eig only; hf4 and hf2d: their normal form only.\n"
    "  glint-mpi help | version\n";

/* What the command line asked for. */
typedef struct mpi_args {
    fit_opts o;
    const char *scene_path, *paintings, *views;
    int threads, force, quiet;
} mpi_args;

/* Parse on every rank (the same argv gives the same answer); messages only
 * from rank 0.  0, or an exit status. */
static int parse_args(int argc, char **argv, mpi_args *a)
{
    static const struct option own[] = {{"paintings", required_argument, 0, 'p'},
                                        {"views", required_argument, 0, 'v'},
                                        {"threads", required_argument, 0, 't'},
                                        {"force", no_argument, 0, 'f'},
                                        {"quiet", no_argument, 0, 'q'},
                                        {"cache", required_argument, 0, 'C'}};
    struct option *lo = fit_opts_table(own, 6);
    int c, rc = 0;

    if (!lo)
        return fail(1, "out of memory");
    optind = 1;
    opterr = my_rank == 0;
    while (rc == 0 && (c = getopt_long(argc, argv, "p:v:t:fq", lo, NULL)) != -1) {
        if (c == 'p') a->paintings = optarg;
        else if (c == 'v') a->views = optarg;
        else if (c == 't') rc = parse_int(optarg, "--threads", 1, PATTERN_MAX_THREADS, &a->threads);
        else if (c == 'f') a->force = 1;
        else if (c == 'q') a->quiet = 1;
        else if (c == 'C') a->o.cache_dir = optarg;
        else if ((rc = fit_opt(&a->o, c, optarg)) < 0)
            rc = fail(1, "%s", usage_text);
    }
    free(lo);
    if (rc)
        return rc;
    if (optind != argc - 1)
        return fail(1, "expected one scene file\n%s", usage_text);
    a->scene_path = argv[optind];
    if (a->paintings && a->views)
        return fail(1, "--paintings and --views both choose the views: give one");
    if (!a->o.cache_dir)
        return fail(1, "a cache directory is needed (--cache-dir DIR; --no-cache makes no sense "
                       "here, and neither HOME nor XDG_CACHE_HOME is set)");
    if ((rc = fit_opts_resolve(&a->o)))
        return rc;
    if (a->o.m != &method_hf3 && a->o.m != &method_hf4 && a->o.m != &method_hf2d)
        return fail(1, "--method %s: glint-mpi decomposes hf3's, hf4's and hf2d's constraint "
                       "matrices only", a->o.m->name);
    if (a->o.m == &method_hf3 && ((const fit_params *)a->o.params)->route != HF_ROUTE_EIG)
        return fail(1, "--route svd: glint-mpi runs the eig route only (the svd route is "
                       "the single-process reference)");
    return 0;
}

/* The views flagged in use[nviews] (OUT), from --paintings, --views or all. */
static int choose_views(const mpi_args *a, const scene *sc, unsigned char *use)
{
    int nused = 0;

    memset(use, a->paintings || a->views ? 0 : 1, (size_t)sc->nviews);
    if (a->paintings) {
        for (int v = 0; v < sc->nviews; v++) {
            char path[4096];
            use[v] = (unsigned char)find_painting(a->paintings, v, path, sizeof path);
        }
    } else if (a->views) {
        const char *p = a->views;
        while (*p) {
            char *end;
            long v;
            errno = 0;
            v = strtol(p, &end, 10);
            if (end == p || errno || v < 0 || v >= sc->nviews || (*end && *end != ','))
                return fail(1, "--views '%s': expected view numbers in 0..%d separated by commas",
                            a->views, sc->nviews - 1);
            use[v] = 1;
            p = *end ? end + 1 : end;
        }
    }
    for (int v = 0; v < sc->nviews; v++)
        nused += use[v];
    if (!nused)
        return a->paintings ? fail(1, "no painting in %s for the scene's %d views (expected "
                                      "view_00.exr, ...)", a->paintings, sc->nviews)
                            : fail(1, "--views '%s' chooses no view", a->views);
    return 0;
}

/* Threads for this rank's rasterizing: the node's cores over its ranks. */
static int default_threads(void)
{
    MPI_Comm node;
    int per_node = 1;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);

    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
    MPI_Comm_size(node, &per_node);
    MPI_Comm_free(&node);
    cores = cores > 0 ? cores / per_node : 1;
    return cores < 1 ? 1 : cores > PATTERN_MAX_THREADS ? PATTERN_MAX_THREADS : (int)cores;
}

/* Collective: an outcome every rank agrees on, printed by rank 0.  0, or
 * the exit status. */
static int agree(int rc, glint_err *e)
{
    if ((rc = hf_mpi_agree(MPI_COMM_WORLD, rc, e)) == 0)
        return 0;
    if (my_rank == 0)
        return fail_err(e);
    return status_of(e->code);
}

/* What each rank reports. */
typedef struct rank_figures {
    double views, samples, t_pattern, t_design, t_gram, rss_mb, bytes_local, bytes_work;
} rank_figures;
#define RANK_FIGURES (sizeof(rank_figures) / sizeof(double))

static double peak_rss_mb(void)
{
    struct rusage ru;
    return getrusage(RUSAGE_SELF, &ru) ? 0.0 : ru.ru_maxrss / 1024.0; /* KiB on Linux */
}

/* What the report says of a decomposition, whichever method made it. */
typedef struct summary {
    int nsamples, n, rank, gauge_dims, null_dims, weak_dims;
    double lambda, rcond, s_max, s_min;
    const char *form;
} summary;

static void report(const mpi_args *a, const char *key, const char *path, const char *phash,
                   const summary *dc, const hf_mpi_stats *st, const rank_figures *all,
                   double t_save, double t_total)
{
    json_t *per = json_array(), *j;
    double tp = 0, td = 0, tg = 0, rss = 0;

    for (int r = 0; r < nranks; r++) {
        const rank_figures *f = &all[r];
        tp = f->t_pattern > tp ? f->t_pattern : tp;
        td = f->t_design > td ? f->t_design : td;
        tg = f->t_gram > tg ? f->t_gram : tg;
        rss = f->rss_mb > rss ? f->rss_mb : rss;
        json_array_append_new(per, json_pack("{s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:f, s:f}",
            "rank", r, "views", (int)f->views, "samples", (int)f->samples,
            "pattern_seconds", f->t_pattern, "design_seconds", f->t_design,
            "gram_seconds", f->t_gram, "peak_rss_mb", f->rss_mb,
            "matrix_mb", f->bytes_local / 1048576.0, "workspace_mb", f->bytes_work / 1048576.0));
    }
    j = json_pack("{s:s, s:s, s:s, s:s, s:i, s:s, s:i, s:f, s:f, s:i, s:i, s:i, s:i, s:f, s:f,"
                  " s:i, s:[i, i], s:i, s:i, s:o, s:o}",
        "scene", a->scene_path, "key", key, "file", path, "pattern_hash", phash,
        "samples", dc->nsamples, "method", a->o.m->name, "n", dc->n, "lambda", dc->lambda,
        "rcond", dc->rcond, "rank", dc->rank, "gauge_dims", dc->gauge_dims,
        "null_dims", dc->null_dims, "weak_dims", dc->weak_dims,
        "s_max", dc->s_max, "s_min", dc->s_min,
        "ranks", nranks, "grid", st->nprow, st->npcol, "block", st->nb,
        "gain_dirs", st->gain_dirs,
        "seconds", json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f}",
            "pattern", tp, "design", td, "gram", tg, "wait", st->t_wait, "reduce", st->t_reduce,
            "eig", st->t_eig, "gather", st->t_gather, "keep", st->t_gain, "save", t_save,
            "total", t_total),
        "per_rank", per);
    json_object_set_new(j, "peak_rss_mb_max", json_real(rss));
    if (dc->form) { /* hfx's counts: unreached unknowns, no gain cut */
        json_object_set_new(j, "form", json_string(dc->form));
        json_object_set_new(j, "unreached", json_integer(dc->weak_dims));
        json_object_del(j, "weak_dims");
    }
    if (j && !a->quiet)
        print_json(j);
    json_decref(j);
}

/* This rank's share of the used views: its pattern and design.  OUT: *d
 * (0 rows when it has no view or its views have no sample). */
/* This rank's design: hf3's (d3), hf4's (d4) or hf2d's (d2), as the
 * method says. */
typedef struct designs {
    hf_design d3;
    hf4_design d4;
    hf2d_design d2;
} designs;

static int local_share(const mpi_args *a, const scene *sc, const char *shash,
                       const unsigned char *use, int threads, designs *ds, rank_figures *f,
                       glint_err *e)
{
    int is4 = a->o.m == &method_hf4, is2d = a->o.m == &method_hf2d;
    int res = is4    ? ((const hf4_params_t *)a->o.params)->res
              : is2d ? ((const hf2d_params_t *)a->o.params)->res
                     : ((const fit_params *)a->o.params)->res;
    unsigned char *mine = calloc((size_t)sc->nviews, 1);
    samples s;
    int k = 0, rc = 0;
    double t0 = MPI_Wtime();

    memset(&s, 0, sizeof s);
    memset(ds, 0, sizeof *ds);
    ds->d3.res = res;
    ds->d4.d.res = res;
    if (is4)
        ds->d4.sres = ((const hf4_params_t *)a->o.params)->sres;
    if (!mine)
        return glint_err_set(e, GLINT_ENOMEM, "out of memory");
    for (int v = 0; v < sc->nviews; v++)
        if (use[v] && k++ % nranks == my_rank) {
            mine[v] = 1;
            f->views++;
        }
    if (f->views > 0) {
        pattern_in in = {sc, mine, a->o.m->pattern_rule, shash, 0, threads, NULL, NULL};
        rc = pattern_raster(&in, &s, e);
        /* views that give no sample leave this rank without rows; the whole
         * pattern having none is found when the counts are summed */
        if (rc == GLINT_EINVAL && strstr(e->msg, "no lit, visible pixel"))
            rc = 0;
    }
    f->t_pattern = MPI_Wtime() - t0;
    t0 = MPI_Wtime();
    if (is2d) { /* a rank without samples still has the shape */
        ds->d2.sh = hf2d_shape_of(a->o.params);
        hf2d_offsets(&ds->d2.sh, ds->d2.off);
    }
    if (rc == 0 && s.n > 0) {
        if (is2d) {
            hf2d_shape sh = hf2d_shape_of(a->o.params);
            rc = hf2d_design_build(&s, &sh, &ds->d2, e);
        } else {
            rc = is4 ? hf4_design_build(&s, res, ds->d4.sres, &ds->d4, e)
                     : hf_design_build(&s, res, &ds->d3, e);
        }
    }
    f->t_design = MPI_Wtime() - t0;
    f->samples = is4 ? ds->d4.d.n : is2d ? ds->d2.n : ds->d3.n;
    samples_free(&s);
    free(mine);
    return rc;
}

/* The cache file glint fit reads for these options (OUT: key, path). */
static int cache_file(const mpi_args *a, const char *phash, char *key, size_t klen, char *path,
                      size_t plen, glint_err *e)
{
    if (a->o.m == &method_hf4 || a->o.m == &method_hf2d) {
        char name[64];
        if (a->o.m == &method_hf4)
            hf4_level_key(a->o.params, phash, key, klen);
        else
            hf2d_level_key(a->o.params, phash, key, klen);
        cfile_name(key, a->o.m == &method_hf4 ? ".hf4" : ".hf2d", name, sizeof name);
        if ((size_t)snprintf(path, plen, "%s/%s", a->o.cache_dir, name) >= plen)
            return glint_err_set(e, GLINT_ERANGE, "cache path too long");
        return 0;
    } else {
        const fit_params *p = a->o.params;
        char k[33];
        pcache_key_hf(phash, p->res, p->lambda, p->route, p->rcond, k);
        snprintf(key, klen, "%s", k);
        return pcache_path(a->o.cache_dir, k, path, plen, e);
    }
}

/* Rank 0: 1 (reported) when the decomposition is on disk already: hf3's
 * read and checked, hf4's and hf2d's present (a damaged one is rebuilt by
 * the fit that reads it). */
static int already_cached(const mpi_args *a, const char *key, const char *path)
{
    hf_decomp old;
    glint_err e;

    if (a->force || access(path, R_OK) != 0)
        return 0;
    if (a->o.m == &method_hf4 || a->o.m == &method_hf2d) {
        if (!a->quiet)
            printf("{\"key\": \"%s\", \"file\": \"%s\", \"cached\": true}\n", key, path);
        return 1;
    }
    if (pcache_decomp_load(a->o.cache_dir, key, &old, &e) != 0)
        return 0;
    if (!a->quiet)
        printf("{\"key\": \"%s\", \"file\": \"%s\", \"cached\": true, \"samples\": %d, "
               "\"rank\": %d}\n", key, path, old.nsamples, old.rank);
    hf_decomp_free(&old);
    return 1;
}

/* The hfx operator (hf4's and hf2d's normal form) of `rows` over the ranks,
 * with gauge_dims gauge directions; *sum filled on rank 0. */
static int build_hfx(hfx_rows *rows, long total, double rcond, int gauge_dims, double lambda,
                     hfx_decomp *x, summary *sum, hf_mpi_stats *st, glint_err *e)
{
    int rc = agree(hfx_mpi_decomp_build(MPI_COMM_WORLD, rows, total,
                                        rcond > 0.0 ? rcond : HF4_RCOND_DEFAULT, gauge_dims, x,
                                        st, e), e);
    if (rc == 0 && my_rank == 0) {
        summary su = {x->nsamples, x->n, x->rank, x->gauge_dims, x->null_dims, x->unreached,
                      lambda, x->rcond, x->s_max, x->s_min_kept, x->form};
        *sum = su;
    }
    return rc;
}

/* Collective: the distributed decomposition of every rank's design ds
 * (total samples), saved by rank 0 under key.  OUT: *sum (rank 0), *st,
 * *t_save. */
static int build_and_save(const mpi_args *a, designs *ds, long total, const char *key,
                          summary *sum, hf_mpi_stats *st, double *t_save, glint_err *e)
{
    int rc = 0;
    double t0;

    memset(sum, 0, sizeof *sum);
    if (a->o.m == &method_hf4) {
        const hf4_params_t *p = a->o.params;
        hf4_rows_ctx ctx;
        hf4_decomp dc = {p->res, p->sres, p->lambda, p->lambda_s, {0}};
        /* the smoothing rows once, on rank 0 */
        hfx_rows rows = hf4_rows(&ds->d4, my_rank == 0 ? p->lambda : 0.0,
                                 my_rank == 0 ? p->lambda_s : 0.0, &ctx);
        if ((rc = build_hfx(&rows, total, p->rcond, 3, p->lambda, &dc.x, sum, st, e)))
            return rc;
        if (my_rank == 0) {
            t0 = MPI_Wtime();
            rc = hf4_decomp_save(&dc, a->o.cache_dir, key, e);
            *t_save = MPI_Wtime() - t0;
        }
        hf4_decomp_free(&dc);
    } else if (a->o.m == &method_hf2d) {
        const hf2d_params_t *p = a->o.params;
        hf2d_rows_ctx ctx;
        hf2d_decomp dc;
        hfx_rows rows;
        memset(&dc, 0, sizeof dc);
        dc.sh = ds->d2.sh;
        dc.lambda = p->lambda;
        dc.lambda_2d = p->lambda_2d;
        /* the smoothing rows once, on rank 0 */
        rows = hf2d_rows(&ds->d2, my_rank == 0 ? p->lambda : 0.0,
                         my_rank == 0 ? p->lambda_2d : 0.0, &ctx);
        if ((rc = build_hfx(&rows, total, p->rcond, 2, p->lambda, &dc.x, sum, st, e)))
            return rc;
        if (my_rank == 0) {
            t0 = MPI_Wtime();
            rc = hf2d_decomp_save(&dc, a->o.cache_dir, key, e);
            *t_save = MPI_Wtime() - t0;
        }
        hf2d_decomp_free(&dc);
    } else {
        const fit_params *p = a->o.params;
        hf_decomp dc;
        if ((rc = agree(hf_mpi_decomp_build(MPI_COMM_WORLD, &ds->d3, total, p->lambda, p->rcond,
                                            &dc, st, e), e)))
            return rc;
        if (my_rank == 0) {
            summary su = {dc.nsamples, dc.n, dc.rank, dc.gauge_dims, dc.null_dims,
                          dc.weak_dims, dc.lambda, dc.rcond, dc.s[0], dc.s[dc.rank - 1], NULL};
            *sum = su;
            t0 = MPI_Wtime();
            rc = pcache_decomp_save(a->o.cache_dir, key, &dc, e);
            *t_save = MPI_Wtime() - t0;
        }
        hf_decomp_free(&dc);
    }
    return agree(rc, e);
}

static int cmd_decompose(int argc, char **argv)
{
    mpi_args a;
    scene sc;
    designs ds;
    summary sum;
    hf_mpi_stats st;
    rank_figures mine, *all = NULL;
    unsigned char *use = NULL;
    char shash[33], phash[33], key[256], path[4096];
    glint_err e;
    int rc = 0, err_fd = -1, cached = 0;
    long total = 0;
    double t_start = MPI_Wtime(), t_save = 0.0;

    memset(&a, 0, sizeof a);
    memset(&sc, 0, sizeof sc);
    memset(&ds, 0, sizeof ds);
    memset(&mine, 0, sizeof mine);
    memset(&e, 0, sizeof e);
    fit_opts_init(&a.o);
    /* every rank parses; only rank 0 speaks */
    if (my_rank != 0) {
        fflush(stderr);
        err_fd = dup(2);
        if (!freopen("/dev/null", "w", stderr))
            err_fd = -1;
    }
    rc = parse_args(argc, argv, &a);
    if (err_fd >= 0) {
        fflush(stderr);
        dup2(err_fd, 2);
        close(err_fd);
        err_fd = -1;
    }
    if (rc)
        goto done;

    rc = agree(scene_load(a.scene_path, &sc, &e), &e);
    if (rc)
        goto done;
    if (!(use = calloc((size_t)sc.nviews, 1))) {
        rc = fail(1, "out of memory");
        goto done;
    }
    if (my_rank != 0) {
        /* the same decision as rank 0's, silently */
        err_fd = dup(2);
        if (!freopen("/dev/null", "w", stderr))
            err_fd = -1;
    }
    rc = choose_views(&a, &sc, use);
    if (err_fd >= 0) {
        fflush(stderr);
        dup2(err_fd, 2);
        close(err_fd);
    }
    if (rc)
        goto done;
    scene_hash(&sc, shash);
    if ((rc = agree(samples_pattern_hash(a.o.m->pattern_rule, shash, use, sc.nviews, phash, &e),
                    &e)) ||
        (rc = agree(cache_file(&a, phash, key, sizeof key, path, sizeof path, &e), &e)))
        goto done;
    if (my_rank == 0)
        cached = already_cached(&a, key, path);
    MPI_Bcast(&cached, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (cached)
        goto done;

    rc = local_share(&a, &sc, shash, use, a.threads > 0 ? a.threads : default_threads(), &ds,
                     &mine, &e);
    if ((rc = agree(rc, &e)))
        goto done;
    {
        long n_local = (long)mine.samples;
        MPI_Allreduce(&n_local, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    }
    if (total < 1) {
        rc = my_rank == 0 ? fail(1, "the chosen views have no lit, visible pixel: nothing to "
                                    "decompose") : 1;
        goto done;
    }
    if ((rc = build_and_save(&a, &ds, total, key, &sum, &st, &t_save, &e)))
        goto done;
    mine.t_gram = st.t_gram;
    mine.bytes_local = st.bytes_local;
    mine.bytes_work = st.bytes_work;
    mine.rss_mb = peak_rss_mb();
    if (my_rank == 0 && !(all = malloc((size_t)nranks * sizeof *all)))
        rc = glint_err_set(&e, GLINT_ENOMEM, "out of memory");
    if ((rc = agree(rc, &e)))
        goto done;
    MPI_Gather(&mine, (int)RANK_FIGURES, MPI_DOUBLE, all, (int)RANK_FIGURES, MPI_DOUBLE, 0,
               MPI_COMM_WORLD);
    if (my_rank == 0)
        report(&a, key, path, phash, &sum, &st, all, t_save, MPI_Wtime() - t_start);
done:
    free(all);
    free(use);
    hf_design_free(&ds.d3);
    hf4_design_free(&ds.d4);
    hf2d_design_free(&ds.d2);
    scene_free(&sc);
    fit_opts_free(&a.o);
    return rc;
}

int main(int argc, char **argv)
{
    int rc;

    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &my_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &nranks);
    if (argc < 2 || !strcmp(argv[1], "help") || !strcmp(argv[1], "--help") ||
        !strcmp(argv[1], "-h")) {
        if (my_rank == 0) {
            fputs(usage_text, argc < 2 ? stderr : stdout);
            if (argc >= 2)
                fit_opts_usage(stdout);
        }
        rc = argc < 2;
    } else if (!strcmp(argv[1], "version") || !strcmp(argv[1], "--version")) {
        if (my_rank == 0)
            puts("glint-mpi " GLINT_MPI_VERSION);
        rc = 0;
    } else if (!strcmp(argv[1], "decompose")) {
        cmd_name = "glint-mpi decompose";
        rc = cmd_decompose(argc - 1, argv + 1);
    } else {
        if (my_rank == 0)
            fprintf(stderr, "glint-mpi: unknown command '%s' (try 'glint-mpi help')\n", argv[1]);
        rc = 1;
    }
    MPI_Finalize();
    return rc;
}
