/* sphere_fixture.h: an analytic unit-sphere G-buffer set for tests of the
 * numerics, independent of glint's rasterizer and scene module: the same
 * construction as ../shared/reference/hf_ref.py (12 icosahedron views at
 * distance 3.5, lights rotated about each view's up axis by
 * linspace(lo, hi) degrees, perspective with margin 1.1). */
#ifndef GLINT_SPHERE_FIXTURE_H
#define GLINT_SPHERE_FIXTURE_H

#include <math.h>
#include <stdlib.h>

#include "gbuf.h"
#include "vec3.h"

static inline void fixture_ico(double d[12][3])
{
    const double P = (1.0 + sqrt(5.0)) / 2.0;
    const double v[12][3] = {{-1, P, 0}, {1, P, 0}, {-1, -P, 0}, {1, -P, 0},
                             {0, -1, P}, {0, 1, P}, {0, -1, -P}, {0, 1, -P},
                             {P, 0, -1}, {P, 0, 1}, {-P, 0, -1}, {-P, 0, 1}};
    for (int i = 0; i < 12; i++) {
        v3 a = v3_normalize(v3_load(v[i]));
        v3_store(a, d[i]);
    }
}

/* Fill gbufs g[0..nv-1] (allocated here) for the analytic sphere.
 * dirs: view directions; light angles lo..hi (linspace). */
static inline int fixture_sphere_gbufs(gbuf *g, int nv, const double (*dirs)[3], double lo,
                                       double hi, int W, int H)
{
    const double D = 3.5, margin = 1.1;
    for (int v = 0; v < nv; v++) {
        v3 dir = v3_normalize(v3_load(dirs[v]));
        v3 eye = v3_scale(dir, D), fwd = v3_scale(dir, -1.0), wu = v3_make(0, 0, 1);
        double ang = nv > 1 ? lo + (hi - lo) * v / (nv - 1.0) : lo;
        if (fabs(fwd.z) > 0.99)
            wu = v3_make(0, 1, 0);
        v3 right = v3_normalize(v3_cross(fwd, wu)), up = v3_cross(right, fwd);
        v3 light = v3_rotate(eye, up, ang * M_PI / 180.0);
        double t = margin / sqrt(D * D - 1.0);
        if (gbuf_alloc(&g[v], W, H, NULL))
            return -1;
        for (int j = 0; j < H; j++) {
            for (int i = 0; i < W; i++) {
                double sx = (2.0 * (i + 0.5) / W - 1.0) * ((double)W / H);
                double sy = 1.0 - 2.0 * (j + 0.5) / H;
                v3 d = v3_normalize(v3_add(fwd, v3_add(v3_scale(right, t * sx),
                                                      v3_scale(up, t * sy))));
                double b = v3_dot(eye, d), c = v3_dot(eye, eye) - 1.0, disc = b * b - c;
                size_t p = (size_t)j * W + i;
                if (!(disc > 0.0))
                    continue;
                double tt = -b - sqrt(disc);
                v3 P = v3_add(eye, v3_scale(d, tt)), n = v3_normalize(P);
                v3 wi = v3_normalize(v3_sub(light, P)), wo = v3_scale(d, -1.0);
                g[v].mask[p] = 1;
                v3_storef(P, g[v].pos + 3 * p);
                v3_storef(n, g[v].nrm + 3 * p);
                v3_storef(wi, g[v].wi + 3 * p);
                v3_storef(wo, g[v].wo + 3 * p);
            }
        }
    }
    return 0;
}

#endif
