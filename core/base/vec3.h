/* vec3.h: small inline 3-vector helpers in double precision.  Header-only;
 * no allocation, no failure modes (normalizing a zero vector gives zero). */
#ifndef GLINT_VEC3_H
#define GLINT_VEC3_H

#include <math.h>

typedef struct v3 { double x, y, z; } v3;

static inline v3 v3_make(double x, double y, double z) { v3 r = {x, y, z}; return r; }
static inline v3 v3_load(const double *p) { return v3_make(p[0], p[1], p[2]); }
static inline v3 v3_loadf(const float *p) { return v3_make(p[0], p[1], p[2]); }
static inline void v3_store(v3 a, double *p) { p[0] = a.x; p[1] = a.y; p[2] = a.z; }
static inline void v3_storef(v3 a, float *p) { p[0] = (float)a.x; p[1] = (float)a.y; p[2] = (float)a.z; }
static inline v3 v3_add(v3 a, v3 b) { return v3_make(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline v3 v3_sub(v3 a, v3 b) { return v3_make(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline v3 v3_scale(v3 a, double s) { return v3_make(a.x * s, a.y * s, a.z * s); }
static inline double v3_dot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline v3 v3_cross(v3 a, v3 b)
{
    return v3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_len(v3 a) { return sqrt(v3_dot(a, a)); }
static inline v3 v3_normalize(v3 a)
{
    double l = v3_len(a);
    return l > 0.0 ? v3_scale(a, 1.0 / l) : a;
}
/* Rodrigues rotation of v about the unit axis `k` by `angle` radians. */
static inline v3 v3_rotate(v3 v, v3 k, double angle)
{
    double c = cos(angle), s = sin(angle);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(k, v), s)),
                  v3_scale(k, v3_dot(k, v) * (1.0 - c)));
}

/* glint's tangent frame at a surface point, from its unit normal alone
 * (what the 2D factors over parabolic maps and the anisotropic Ward truth
 * measure directions in): t = normalize(Z x n), Z the world's up axis
 * (scene.h), so that t runs around the vertical axis (the grooves of a
 * lathe-turned, "spun" finish) and b = n x t along it: on a surface facing
 * +X, t = +Y and b = +Z.  Where n is within 1e-6 of the axis (the two
 * poles, where every field of tangents has a singularity, as a spun finish
 * has at its centre) t = +X.  The GLSL of those materials repeats it. */
static inline void v3_frame(v3 n, v3 *t, v3 *b)
{
    v3 a = v3_make(-n.y, n.x, 0.0); /* Z x n */
    double l = v3_len(a);
    *t = l > 1e-6 ? v3_scale(a, 1.0 / l) : v3_make(1.0, 0.0, 0.0);
    *b = v3_cross(n, *t);
}

#endif
