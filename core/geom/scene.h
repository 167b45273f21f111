/* scene.h: a scene is a mesh, a raster size and a set of views, each view
 * a pinhole camera with its own point light.  A scene and its sampling
 * pattern have a stable content hash, the key of every precomputation.
 *
 * Conventions (shared with ../shared/reference, so numbers compare):
 *  - Camera: eye, looking at `target`; fwd = normalize(target - eye),
 *    right = normalize(fwd x world_up) with world_up = +z (or +y when
 *    |fwd.z| > 0.99), up = right x fwd.  Perspective with vertical
 *    half-angle `half_fov` (radians); pixel (row j, col i), j = 0 at the
 *    top, ray through the pixel centre: sx = (2(i+.5)/W - 1) W/H,
 *    sy = 1 - 2(j+.5)/H, dir = normalize(fwd + tan(half_fov)(sx right + sy up)).
 *  - Default views: the 12 icosahedron vertices in the fixed order of
 *    scene_icosahedron(), at distance 3.5 from the origin, half_fov with
 *    tan = 1.1 / sqrt(3.5^2 - 1) (the unit sphere spans 1/1.1 of the
 *    half-height).  Each view's light is its eye rotated about the view's
 *    up axis (through the origin) by an angle that varies across views
 *    (default linspace(20, 70) degrees), at the same distance.  A constant
 *    angle would make every view of a sphere congruent: the same samples.
 *  - Lights are point lights of constant intensity (no 1/d^2 fall-off).
 *  - Radiance, the one scale every stage uses (painting, base renders,
 *    fits, summaries, previews, exports): a point light of intensity I
 *    makes a white Lambertian surface facing it read I, so a pixel is
 *    pi I f(wi, wo) cos_i for a BRDF f in 1/sr (view_light_scale: pi I).
 *    A Lambertian of albedo a facing a light of intensity 1 reads a, and a
 *    fit of it reads back base colour a.  Under an environment of radiance
 *    L a pixel is the integral of L f cos_i (a white Lambertian under a
 *    uniform sky of radiance 1 reads 1): the same scale, with no pi.
 *
 * Ownership: a scene owns its mesh and views; scene_free() releases them
 * and accepts NULL or a half-built scene.
 * Thread-safety: no global state; a scene is read-only once made, so any
 * number of threads may read, hash, rasterize or save one scene at once;
 * building or freeing one is its owner's, on one thread. */
#ifndef GLINT_SCENE_H
#define GLINT_SCENE_H

#include <stdint.h>

#include "err.h"
#include "mesh.h"

#define SCENE_MAX_VIEWS 256
#define SCENE_MIN_SIZE 8
#define SCENE_MAX_SIZE 4096
#define SCENE_NAME_MAX 64
#define SCENE_PATH_MAX 4096

typedef struct scene_view {
    double eye[3];
    double target[3];
    double half_fov;       /* radians, vertical half-angle, in (0, pi/2) */
    double light[3];       /* point light position */
    double light_intensity;/* > 0, default 1: a white Lambertian facing it reads this */
    double light_deg;      /* how the light was placed (informative; -1 if explicit) */
} scene_view;

/* The radiance of a point light of intensity 1 on a surface facing it,
 * in the units a painted value is in (see Radiance above). */
#define GLINT_LIGHT_UNIT 3.14159265358979323846

/* The factor a view's pixel applies to f(wi, wo) cos_i: pi I. */
static inline double view_light_scale(const scene_view *v)
{
    return GLINT_LIGHT_UNIT * v->light_intensity;
}

typedef struct scene {
    char mesh_name[SCENE_NAME_MAX]; /* a built-in ("sphere", "torus", "teapot"), or the label
                                       of a mesh file (its base name when glint made it) */
    char mesh_path[SCENE_PATH_MAX]; /* "" for a built-in; else the mesh file, absolute */
    mesh mesh;
    mesh_report mesh_info;  /* what mesh_load decided (zeroed for a built-in) */
    int width, height;     /* raster size of every view */
    int nviews;
    scene_view *views;     /* nviews entries */
} scene;

/* Parameters of a scene built from a built-in mesh with the icosahedron
 * view set.  scene_params_default() fills the documented defaults. */
typedef struct scene_params {
    char mesh_name[SCENE_NAME_MAX]; /* built-in mesh, default "sphere" */
    char mesh_path[SCENE_PATH_MAX]; /* default "": the built-in mesh_name; else a mesh file
                                       read with mesh_load (relative: to the working
                                       directory), and mesh_name is ignored: the scene's
                                       name is the file's base name */
    int width, height;     /* default 128 x 128 */
    double distance;       /* camera (and light) distance, default 3.5 */
    double margin;         /* silhouette of the unit ball spans 1/margin of the half-height, default 1.1 */
    double light_lo_deg, light_hi_deg; /* per-view light angles linspace(lo, hi), default 20, 70 */
    int light_mid;         /* 1: use midpoints lo + (hi-lo)(m+.5)/n instead of end points */
    int view_set;          /* SCENE_VIEWS_ICO12 (vertices) or SCENE_VIEWS_ICO20 (face centres) */
} scene_params;

enum { SCENE_VIEWS_ICO12 = 0, SCENE_VIEWS_ICO20 = 1 };

void scene_params_default(scene_params *p);

/* The 12 unit icosahedron vertex directions in glint's fixed order
 * (OUT: dirs[12][3]) and the 20 normalized face centroids in lexicographic
 * face order (OUT: dirs[20][3]).  Both are deterministic. */
void scene_icosahedron(double dirs[12][3]);
void scene_icosahedron_faces(double dirs[20][3]);

/* Build a scene from parameters: the built-in mesh, views on the chosen
 * set, lights placed as described above.  *out is zeroed first. */
int scene_create(const scene_params *p, scene *out, glint_err *err);

/* Make one view: camera at `dir` * distance looking at the origin, light
 * rotated about the view's up axis by light_deg.  (OUT: *v) */
void scene_view_make(const double dir[3], double distance, double margin,
                     double light_deg, scene_view *v);

/* Camera frame of a view (OUT: fwd, right, up, all unit). */
void scene_view_frame(const scene_view *v, double fwd[3], double right[3], double up[3]);

/* Serialize to / from JSON text (jansson).  The JSON holds the mesh by
 * name plus every view explicitly, so a scene file can also describe
 * hand-placed cameras and lights.  scene_to_json returns a malloc'ed
 * NUL-terminated string (caller frees) or NULL with *err set.
 * scene_from_json validates everything (sizes, finiteness, view count,
 * degenerate cameras) and fails with a message naming the field.
 *
 * Meshes from files: an optional "mesh_file" string names the file (read
 * with mesh_load; "mesh" is then only a label).  A relative mesh_file is
 * resolved against the directory of the scene file when read by
 * scene_load, and against the working directory by scene_from_json; the
 * scene keeps the absolute path (scene.mesh_path), which is what
 * scene_to_json and scene_save write, so a saved scene can be moved
 * anywhere on the same machine.  Scenes with a built-in mesh have no
 * "mesh_file" key.  The content hash covers the mesh arrays, not the path:
 * the same file in two places gives the same hash, an edited file a new
 * one.  A scene document can make glint read any file the process can:
 * a server must only accept mesh_file values it chose itself. */
char *scene_to_json(const scene *s, glint_err *err);
int scene_from_json(const char *text, scene *out, glint_err *err);
int scene_load(const char *path, scene *out, glint_err *err);
int scene_save(const scene *s, const char *path, glint_err *err);

/* Stable 128-bit content hash of the scene's geometry and sampling pattern
 * (mesh arrays, raster size, every camera and light, in a fixed byte
 * order), as 32 lowercase hex digits + NUL in OUT hex[33]. */
void scene_hash(const scene *s, char hex[33]);

/* Validate a scene in memory (as scene_from_json does). */
int scene_validate(const scene *s, glint_err *err);

void scene_free(scene *s);

#endif
