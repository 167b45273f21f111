/* cli.h: what the files of the glint command line share.  The program
 * is one file per command group:
 *   main.c        dispatch, usage, version
 *   cli_util.c    messages and exit statuses, argument parsing, the steps
 *                 several commands take (load a scene, rasterize it, read
 *                 paintings, write JSON or a material)
 *   cmd_scene.c   scene, gbuffer, paint, base-render
 *   fit_opts.c    the fit options, from the methods' parameter tables
 *   cmd_fit.c     fit, fit-samples, export-samples
 *   cmd_render.c  render, eval, the exports (shader, MERL, .brdf, glTF,
 *                 MaterialX, USD), and the renderer
 *   cmd_demo.c    demo
 *   cmd_methods.c methods: the catalogue, and each method's JSON Schema
 *
 * Conventions: a command gets argv from its own name on (argv[0] is
 * "fit"), returns the process's exit status, and has printed its message
 * by then: fail() and fail_err() print "glint CMD: message" on stderr and
 * return the status, so helpers below return 0 or that status.  Exit
 * statuses: 1 bad usage or invalid input, 2 I/O error, 3 numerical
 * failure. */
#ifndef GLINT_CLI_H
#define GLINT_CLI_H

#include <stdio.h>

#include <jansson.h>

#include <getopt.h>

#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "material.h"
#include "method.h"
#include "render.h"
#include "scene.h"

/* "glint" or "glint CMD", the prefix of every message (set by main). */
extern const char *cmd_name;

/* ---- messages and exit statuses (cli_util.c) ---------------------------- */

/* Print "cmd_name: message" on stderr; returns `code`. */
int fail(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Exit status for a glint error code. */
int status_of(int code);
/* fail() with e's message (or its code's name) and status_of(e->code). */
int fail_err(const glint_err *e);

/* ---- argument parsing (cli_util.c): 0, or 1 after a message ------------- */

/* A whole number in lo..hi (OUT: *out); `what` names the option. */
int parse_int(const char *s, const char *what, long lo, long hi, int *out);
/* A finite number in [lo, hi] (OUT: *out). */
int parse_double(const char *s, const char *what, double lo, double hi, double *out);
/* Three finite numbers "x,y,z", each of magnitude <= 1e6 (OUT: out). */
int parse_vec3(const char *s, const char *what, double out[3]);
/* A raster size "WxH" or "N" (square), each in SCENE_MIN_SIZE..SCENE_MAX_SIZE. */
int parse_size(const char *s, int *w, int *h);

/* ---- shared steps (cli_util.c): 0, or an exit status after a message ---- */

/* scene_load (OUT: *sc, freed by the caller with scene_free). */
int load_scene(const char *path, scene *sc);
/* raster_scene: every view's G-buffer (OUT: *g, raster_free_all). */
int raster_all(const scene *sc, gbuf **g);
/* Read the paintings of a scene: from a directory `dir` (view_KK.exr,
 * .hdr, .png, .jpg or .jpeg; views without a file are not used) or, when
 * dir is NULL, from `files` (nfiles of them, one per view, in order).
 * imgs and use hold sc->nviews entries (OUT: imgs[v] and use[v] = 1 for
 * each painting read; the caller frees imgs with free_imgs). */
/* DIR/view_KK.exr, .hdr, .png, .jpg or .jpeg if one exists (OUT: path): 1, else 0. */
int find_painting(const char *dir, int view, char *path, size_t len);
int read_paintings(const scene *sc, const char *dir, char **files, int nfiles,
                   img *imgs, unsigned char *use);
/* Free n images and the array.  Accepts NULL. */
void free_imgs(img *imgs, int n);
/* Write j as indented JSON to path, atomically. */
int write_json_file(const char *path, json_t *j);
/* Print j as indented JSON on stdout. */
void print_json(json_t *j);
/* material_save to the directory `out`. */
int save_material(const material *m, const char *out);

/* ---- fit options (fit_opts.c) ---------------------------------------- */

#define FIT_OPTS_MAX 64

/* What the command line says of a fit: a method, its parameters, the cache. */
typedef struct fit_opts {
    const char *method_name;     /* --method, or NULL for the default */
    const method *m;             /* after fit_opts_resolve */
    void *params;                /* the method's params struct (fit_opts_free) */
    const char *cache_dir;       /* NULL: no cache on disk */
    struct {
        const char *name, *value;
    } set[FIT_OPTS_MAX];         /* parameters given, applied by fit_opts_resolve */
    int nset;
} fit_opts;

/* $XDG_CACHE_HOME/glint, else $HOME/.cache/glint, else NULL (no cache).
 * Points to static storage. */
const char *default_cache_dir(void);
void fit_opts_init(fit_opts *o);
/* A getopt table: the command's own `nown` options, then --method,
 * --cache-dir, --no-cache and every parameter of every method (malloc'ed;
 * free()).  NULL when out of memory. */
struct option *fit_opts_table(const struct option *own, int nown);
/* Take option c (from that table): 0 if it was a fit option,
 * GLINT_ENOTFOUND if not, > 0 (an exit status, message printed) on error. */
int fit_opt(fit_opts *o, int c, const char *arg);
/* Pick the method and apply the parameters given: 0 or an exit status. */
int fit_opts_resolve(fit_opts *o);
void fit_opts_free(fit_opts *o);
/* Print the "fit options:" part of the usage on f (from the tables). */
void fit_opts_usage(FILE *f);
/* Fit the paintings imgs of the views flagged in `use` of scene sc with
 * the options' method, through the cache on disk.  OUT: *m.  0 or an exit
 * status. */
int cli_fit_scene(const fit_opts *o, const scene *sc, const unsigned char *use, const img *imgs,
                  material *m);

/* ---- rendering (cmd_render.c) -------------------------------------------- */

/* The process's renderer (EGL opened on first use); NULL only when out of
 * memory. */
render *cli_render(void);
/* Close it if one was opened (main calls it after a command). */
void cli_render_close(void);

/* ---- commands: argv[0] is the command's name; returns the exit status --- */

int cmd_scene(int argc, char **argv);         /* cmd_scene.c */
int cmd_gbuffer(int argc, char **argv);
int cmd_paint(int argc, char **argv);
int cmd_base_render(int argc, char **argv);
int cmd_fit(int argc, char **argv);           /* cmd_fit.c */
int cmd_fit_samples(int argc, char **argv);
int cmd_fit_gbuffers(int argc, char **argv);
int cmd_export_samples(int argc, char **argv);
int cmd_render(int argc, char **argv);        /* cmd_render.c */
int cmd_eval(int argc, char **argv);
int cmd_summary(int argc, char **argv);
int cmd_export_shader(int argc, char **argv);
int cmd_export_merl(int argc, char **argv);
int cmd_export_brdf(int argc, char **argv);
int cmd_export_gltf(int argc, char **argv);
int cmd_export_mtlx(int argc, char **argv);
int cmd_export_usda(int argc, char **argv);
int cmd_export_usdz(int argc, char **argv);
int cmd_export_mtlx_zip(int argc, char **argv);
int cmd_demo(int argc, char **argv);          /* cmd_demo.c */
int cmd_methods(int argc, char **argv);       /* cmd_methods.c */

#endif
