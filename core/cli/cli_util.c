/* cli_util.c: what the glint commands share (cli.h): messages and exit
 * statuses, argument parsing, and the steps several commands take. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "fsio.h"
#include "raster.h"

/* ---- messages and exit statuses --------------------------------------------- */

const char *cmd_name = "glint";

int fail(int code, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", cmd_name);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

/* Exit status for a glint error code. */
int status_of(int code)
{
    switch (code) {
    case GLINT_EIO: return 2;
    case GLINT_ENUMERIC: case GLINT_EINTERNAL: return 3;
    default: return 1;
    }
}

int fail_err(const glint_err *e)
{
    return fail(status_of(e->code), "%s", e->msg[0] ? e->msg : glint_strerror(e->code));
}

/* ---- argument parsing ------------------------------------------------------- */

int parse_int(const char *s, const char *what, long lo, long hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        return fail(1, "%s '%s' must be a whole number in %ld..%ld", what, s, lo, hi);
    *out = (int)v;
    return 0;
}

int parse_double(const char *s, const char *what, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return fail(1, "%s '%s' must be a finite number in [%g, %g]", what, s, lo, hi);
    *out = v;
    return 0;
}

int parse_vec3(const char *s, const char *what, double out[3])
{
    char *end;
    const char *p = s;
    for (int i = 0; i < 3; i++) {
        out[i] = strtod(p, &end);
        if (end == p || !isfinite(out[i]) || fabs(out[i]) > 1e6)
            return fail(1, "%s '%s' must be three finite numbers x,y,z", what, s);
        p = end;
        if (i < 2) {
            if (*p != ',')
                return fail(1, "%s '%s' must be three numbers separated by commas", what, s);
            p++;
        }
    }
    if (*p)
        return fail(1, "%s '%s' has trailing characters", what, s);
    return 0;
}

int parse_size(const char *s, int *w, int *h)
{
    int n1, n2;
    char x;
    if (sscanf(s, "%d%c%d", &n1, &x, &n2) == 3 && (x == 'x' || x == 'X')) {
        char buf[64];
        snprintf(buf, sizeof buf, "%dx%d", n1, n2);
        if (strcmp(buf, s) != 0)
            return fail(1, "size '%s' must be WxH or N", s);
    } else {
        if (parse_int(s, "size", SCENE_MIN_SIZE, SCENE_MAX_SIZE, &n1))
            return 1;
        n2 = n1;
    }
    if (n1 < SCENE_MIN_SIZE || n1 > SCENE_MAX_SIZE || n2 < SCENE_MIN_SIZE || n2 > SCENE_MAX_SIZE)
        return fail(1, "size %dx%d outside %d..%d", n1, n2, SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    *w = n1;
    *h = n2;
    return 0;
}

/* ---- shared steps ----------------------------------------------------------- */

int load_scene(const char *path, scene *sc)
{
    glint_err e;
    if (scene_load(path, sc, &e))
        return fail_err(&e);
    return 0;
}

int raster_all(const scene *sc, gbuf **g)
{
    glint_err e;
    if (raster_scene(sc, g, &e))
        return fail_err(&e);
    return 0;
}

/* Find view_KK.{exr,hdr,png,jpg,jpeg} in dir; returns 1 and the path if found (cli.h). */
int find_painting(const char *dir, int view, char *path, size_t len)
{
    static const char *ext[] = {"exr", "hdr", "png", "jpg", "jpeg"};
    struct stat st;
    for (unsigned i = 0; i < sizeof ext / sizeof ext[0]; i++) {
        snprintf(path, len, "%s/view_%02d.%s", dir, view, ext[i]);
        if (stat(path, &st) == 0)
            return 1;
    }
    return 0;
}

/* Read the paintings of a scene: from a directory (views without a file are
 * not used) or from a list of files (one per view, in order). */
int read_paintings(const scene *sc, const char *dir, char **files, int nfiles,
                   img *imgs, unsigned char *use)
{
    glint_err e;
    int found = 0;
    if (!dir && nfiles != sc->nviews)
        return fail(1, "expected %d painting files (one per view), got %d; or use --paintings DIR",
                    sc->nviews, nfiles);
    for (int v = 0; v < sc->nviews; v++) {
        char path[4096];
        const char *p = NULL;
        use[v] = 0;
        if (dir) {
            if (find_painting(dir, v, path, sizeof path))
                p = path;
        } else {
            p = files[v];
        }
        if (!p)
            continue;
        if (img_read(p, &imgs[v], &e)) {
            glint_err_prefix(&e, "painting of view %d (%s)", v, p);
            return fail_err(&e);
        }
        if (imgs[v].width != sc->width || imgs[v].height != sc->height)
            return fail(1, "painting %s is %dx%d but the scene renders %dx%d", p, imgs[v].width,
                        imgs[v].height, sc->width, sc->height);
        use[v] = 1;
        found++;
    }
    if (!found)
        return fail(1, "no painting found in %s (expected view_00.exr, view_01.png, ...)", dir);
    return 0;
}

void free_imgs(img *imgs, int n)
{
    if (!imgs)
        return;
    for (int i = 0; i < n; i++)
        img_free(&imgs[i]);
    free(imgs);
}

int write_json_file(const char *path, json_t *j)
{
    glint_err e;
    char *text = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    int rc;
    if (!text)
        return fail(1, "cannot serialize JSON");
    rc = fsio_write_atomic(path, text, strlen(text), &e);
    free(text);
    return rc ? fail_err(&e) : 0;
}

void print_json(json_t *j)
{
    char *text = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(17));
    if (text) {
        puts(text);
        free(text);
    }
}

/* ---- materials -------------------------------------------------------------- */

int save_material(const material *m, const char *out)
{
    glint_err e;
    if (material_save(m, out, &e))
        return fail_err(&e);
    return 0;
}
