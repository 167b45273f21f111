/* env.h: environment lighting: HDR environment maps, built-in procedural
 * skies, rotation and intensity, and the compression of a map into a few
 * hundred directional lights (the lights every environment-lit
 * precomputation sums over).
 *
 * Conventions (shared with ../shared/reference/srbf_ref.py, so numbers
 * compare):
 *  - Lat-long layout, z up, row 0 at the top (Blender/Cycles'
 *    equirectangular world mapping): for a W x H map, pixel (r, c) has
 *    theta = pi (r + .5) / H (polar angle from +z) and
 *    phi = pi - 2 pi (c + .5) / W, d = (sin theta cos phi,
 *    sin theta sin phi, cos theta).  The centre column looks along +x.
 *    The solid angle of a pixel of row r is exactly
 *    (2 pi / W)(cos theta_top - cos theta_bottom); they sum to 4 pi.
 *  - Radiance is linear RGB, per steradian.  A light's `power` is radiance
 *    times solid angle (what eq. 21 of Iwasaki et al. sums): an integral
 *    over incident directions is sum_k power_k * integrand(dir_k).
 *  - Rotation by psi (radians) about +z maps a direction d to Rz(psi) d
 *    (counter-clockwise seen from +z): the rotated map is
 *    L'(w) = L(Rz(-psi) w).  Intensity scales radiance.
 *
 * Ownership: env_* fill caller-provided structs whose arrays they
 * allocate; env_map_free / env_lights_free release them (NULL and zeroed
 * structs accepted).  Thread-safety: no global state except the resolver,
 * which is set once before threads start; maps and lights are read-only
 * once made. */
#ifndef GLINT_ENV_H
#define GLINT_ENV_H

#include <stddef.h>

#include "err.h"
#include "img.h"

#define ENV_MAX_DIM 8192      /* of a lat-long map, and 4 x a cube face */
#define ENV_MAX_LIGHTS 65536
#define ENV_NAME_MAX 64

typedef struct env_map {
    int width, height;        /* lat-long, width = 2 height */
    float *rgb;               /* width x height x 3 radiance, row 0 at the top */
    char name[ENV_NAME_MAX];  /* "sky", "courtyard.exr", ... */
    long clamped;             /* negative texels set to 0 when read */
    long nonfinite;           /* non-finite texels set to 0 when read */
    char layout[16];          /* what the source was: "latlong", "cross", "builtin" */
} env_map;

/* Read an HDR file (OpenEXR including DWAB, Radiance HDR, or any format
 * img.h reads) in lat-long (2:1) or cube-cross (horizontal 4:3 or vertical
 * 3:4) layout; a cross is resampled to a lat-long map of width 4 x face.
 * Negative texels (lossy compression) are clamped to 0, non-finite ones set
 * to 0, and both counted in the result; a map whose every texel is 0 is
 * accepted (an unlit scene).  Other aspect ratios: GLINT_EINVAL naming the
 * layouts accepted. */
int env_load(const char *path, env_map *out, glint_err *err);
/* From memory (an upload), the file's sides at most max_dim, its header
 * seen by check(cls, header) first when check is not NULL
 * (img_read_mem_checked). */
int env_load_mem(const void *data, size_t len, const char *name, int max_dim,
                 img_header_check check, void *cls, env_map *out, glint_err *err);

/* A built-in procedural map, width x height lat-long (width = 2 height,
 * height 8..ENV_MAX_DIM/2): "sky" (a clear sky with a sun), "studio"
 * (neutral: a grey dome with two soft boxes), "sunset" (low warm sun),
 * "white" (constant radiance 1: the furnace test), "overcast".
 * GLINT_ENOTFOUND naming the built-ins otherwise. */
int env_builtin(const char *name, int width, int height, env_map *out, glint_err *err);
/* The built-ins' names, comma-separated. */
const char *env_builtin_names(void);

/* An environment by specification: "builtin:<name>" or "<name>" of a
 * built-in (at 512 x 256), else what the resolver set by the host
 * (env_set_resolver) maps the spec to: a file path it vouches for.  With
 * no resolver, other specs give GLINT_ENOTFOUND.  A server's resolver
 * must only map specs to files it owns. */
typedef int (*env_resolver)(const char *spec, char *path, size_t len, glint_err *err);
void env_set_resolver(env_resolver fn);
int env_resolve(const char *spec, env_map *out, glint_err *err);
/* Whether env_resolve would find spec, without loading anything: 0 for a
 * built-in or a spec the resolver maps to a file (whether the file holds a
 * usable map is found when it is read); otherwise env_resolve's error
 * (GLINT_EINVAL for the syntax, GLINT_ENOTFOUND naming what is offered). */
int env_spec_lookup(const char *spec, glint_err *err);
/* A spec's syntax check without loading (0, or GLINT_EINVAL saying why):
 * at most ENV_NAME_MAX - 1 bytes of [A-Za-z0-9._:/-] (what a spec names
 * beyond that is the resolver's to check). */
int env_spec_check(const char *spec, glint_err *err);

/* What env_resolve would read for spec, as a string that changes when it
 * does (OUT: out, at most len bytes): "builtin:NAME", or for a file the
 * resolver's path with its device, inode, size and modification time.
 * 0, or env_resolve's error. */
int env_identity(const char *spec, char *out, size_t len, glint_err *err);

/* Radiance in direction d (unit) of the map rotated by psi and scaled by
 * intensity, bilinear (OUT: rgb). */
void env_radiance(const env_map *m, const double d[3], double psi, double intensity,
                  double rgb[3]);

/* Sum of radiance x solid angle over the map, i.e. 4 pi x mean radiance
 * (OUT: rgb). */
void env_total_power(const env_map *m, double rgb[3]);

/* ---- compression into lights -------------------------------------------------- */

typedef struct env_lights {
    int k;
    double *dir;              /* 3k unit directions */
    double *power;            /* 3k RGB powers (radiance x solid angle) */
    double total[3];          /* sum of the powers */
} env_lights;

typedef enum {
    ENV_CUT_MEDIAN = 0,       /* Debevec's median cut, exactly k lights */
    ENV_CUT_LATLONG = 1       /* solid-angle box filter to a w x w/2 map: k = w^2/2 */
} env_cut;

/* Compress the map rotated by psi and scaled by intensity into k lights.
 * Median cut (reference conventions): on the map box-filtered to at most
 * 512 x 256, each pass splits every region in two along its longer side
 * (width = sin(theta_centre) x angular width) where the luminance power
 * (Y = 0.2126 R + 0.7152 G + 0.0722 B, times solid angle) is halved, a
 * pass stopping once k would be exceeded, single texels never split; each
 * light sits at the luminance-power-weighted mean direction of its region
 * (normalized) and carries the region's exact RGB power, so total power is
 * kept exactly.  Regions of zero power give lights of zero power.
 * Lat-long: k must be w^2/2 for an even w <= the map's width.
 * k in 1..ENV_MAX_LIGHTS (GLINT_ERANGE otherwise). */
int env_compress(const env_map *m, env_cut how, int k, double psi, double intensity,
                 env_lights *out, glint_err *err);

/* env_resolve then env_compress, kept for the next call with the same
 * spec and settings (env_cache.c): copies of the map and its lights (OUT:
 * map, lights; the caller frees them), the same as the two calls give.
 * A file behind spec that changes on disk is read again.  Thread-safe. */
int env_prepare(const char *spec, env_cut how, int k, double psi, double intensity,
                env_map *map, env_lights *lights, glint_err *err);
/* Drop everything env_prepare keeps (tests; a host freeing memory). */
void env_cache_clear(void);

/* Rotate lights by psi about +z (in place). */
void env_lights_rotate(env_lights *l, double psi);

/* How well lights stand for the map they came from (same psi and
 * intensity): relative RMS errors, over 256 Fibonacci directions n, of
 * the irradiance sum L max(0, n.d) domega and of a glossy convolution
 * sum L exp(lambda (n.d - 1)) domega (lambda = 81: a sigma = pi/40 lobe),
 * both against the full map (box-filtered to at most 256 x 128). */
typedef struct env_cut_error {
    double irradiance_rel_rms;
    double glossy_rel_rms;
} env_cut_error;
int env_compress_error(const env_map *m, const env_lights *l, double psi, double intensity,
                       env_cut_error *out, glint_err *err);

void env_map_free(env_map *m);
void env_lights_free(env_lights *l);

#endif
