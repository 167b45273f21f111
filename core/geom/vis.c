/* vis.c: visibility by ray casting with Embree 3, and convexity (vis.h).
 *
 * The mesh's positions and triangles are copied into Embree's buffers, so
 * the mesh may be freed after vis_open.  Rays are occlusion rays cast one
 * at a time (rtcOccluded1) by `nthreads` threads, each over a contiguous
 * range of points. */
#include "vis.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <xxhash.h>

struct vis_scene {
    RTCDevice dev;
    RTCScene scn;
    double eps;
};

static void on_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    (void)code;
    (void)str;
}

int vis_open(const mesh *m, vis_scene **out, glint_err *err)
{
    vis_scene *v;
    RTCGeometry geo;
    float *vb;
    unsigned *ib;
    double r2 = 0.0;

    *out = NULL;
    if (!m || m->nverts < 3 || m->ntris < 1)
        return glint_err_set(err, GLINT_EINVAL, "visibility needs a mesh with triangles");
    if (!(v = calloc(1, sizeof *v)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    v->dev = rtcNewDevice("verbose=0");
    if (!v->dev) {
        free(v);
        return glint_err_set(err, GLINT_EUNSUPPORTED, "Embree could not start (error %d)",
                             (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceErrorFunction(v->dev, on_error, NULL);
    v->scn = rtcNewScene(v->dev);
    rtcSetSceneBuildQuality(v->scn, RTC_BUILD_QUALITY_MEDIUM);
    geo = rtcNewGeometry(v->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    vb = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                 3 * sizeof(float), (size_t)m->nverts);
    ib = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                 3 * sizeof(unsigned), (size_t)m->ntris);
    if (!vb || !ib) {
        rtcReleaseGeometry(geo);
        vis_close(v);
        return glint_err_set(err, GLINT_ENOMEM, "Embree could not allocate the mesh (error %d)",
                             (int)rtcGetDeviceError(v ? NULL : NULL));
    }
    for (int i = 0; i < 3 * m->nverts; i++) {
        if (!isfinite(m->pos[i])) {
            rtcReleaseGeometry(geo);
            vis_close(v);
            return glint_err_set(err, GLINT_EINVAL, "mesh position %d is not finite", i / 3);
        }
        vb[i] = m->pos[i];
    }
    for (int i = 0; i < m->nverts; i++) {
        const float *p = m->pos + 3 * i;
        double d = (double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2];
        r2 = d > r2 ? d : r2;
    }
    for (int i = 0; i < 3 * m->ntris; i++) {
        if (m->tri[i] >= (uint32_t)m->nverts) {
            rtcReleaseGeometry(geo);
            vis_close(v);
            return glint_err_set(err, GLINT_EINVAL, "triangle %d has a bad vertex index", i / 3);
        }
        ib[i] = m->tri[i];
    }
    rtcCommitGeometry(geo);
    rtcAttachGeometry(v->scn, geo);
    rtcReleaseGeometry(geo);
    rtcCommitScene(v->scn);
    if (rtcGetDeviceError(v->dev) != RTC_ERROR_NONE) {
        vis_close(v);
        return glint_err_set(err, GLINT_ENOMEM, "Embree could not build the scene");
    }
    v->eps = VIS_EPS * (r2 > 0.0 ? sqrt(r2) : 1.0);
    *out = v;
    return 0;
}

void vis_close(vis_scene *v)
{
    if (!v)
        return;
    if (v->scn)
        rtcReleaseScene(v->scn);
    if (v->dev)
        rtcReleaseDevice(v->dev);
    free(v);
}

typedef struct vjob {
    const vis_scene *v;
    const float *pos, *nrm;
    const double *dirs;
    int k, i0, i1;
    uint64_t *bits;
    long rays;
    const glint_cancel *cancel;
    int *stopped;             /* shared by the threads: set once one was told to stop */
} vjob;

static void *vjob_run(void *arg)
{
    vjob *j = arg;
    int words = VIS_WORDS(j->k);
    struct RTCIntersectContext ctx;
    long every = glint_cancel_every(j->k);
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    for (int i = j->i0; i < j->i1; i++) {
        const float *p = j->pos + 3 * (size_t)i, *n = j->nrm + 3 * (size_t)i;
        if (j->cancel && (i - j->i0) % every == 0) {
            if (__atomic_load_n(j->stopped, __ATOMIC_RELAXED))
                break;
            if (glint_cancelled(j->cancel)) {
                __atomic_store_n(j->stopped, 1, __ATOMIC_RELAXED);
                break;
            }
        }
        uint64_t *b = j->bits + (size_t)i * words;
        double o[3];
        memset(b, 0, (size_t)words * sizeof *b);
        for (int e = 0; e < 3; e++)
            o[e] = p[e] + j->v->eps * n[e];
        for (int k = 0; k < j->k; k++) {
            const double *d = j->dirs + 3 * k;
            struct RTCRay ray;
            if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0.0)
                continue;
            memset(&ray, 0, sizeof ray);
            ray.org_x = (float)o[0];
            ray.org_y = (float)o[1];
            ray.org_z = (float)o[2];
            ray.dir_x = (float)d[0];
            ray.dir_y = (float)d[1];
            ray.dir_z = (float)d[2];
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            ray.mask = 0xFFFFFFFFu;
            rtcOccluded1(j->v->scn, &ctx, &ray);
            j->rays++;
            if (ray.tfar >= 0.0f)
                b[k >> 6] |= (uint64_t)1 << (k & 63);
        }
    }
    return NULL;
}

int vis_compute(const vis_scene *v, int npoints, const float *pos, const float *nrm, int k,
                const double *dirs, uint64_t *bits, int nthreads, long *rays,
                const glint_cancel *cancel, glint_err *err)
{
    long nc = nthreads > 0 ? nthreads : sysconf(_SC_NPROCESSORS_ONLN);
    int nt = nc < 1 ? 1 : nc > 64 ? 64 : (int)nc, stopped = 0;
    pthread_t th[64];
    vjob jobs[64];
    long total = 0;

    if (!v || npoints < 0 || k < 1 || k > 65536)
        return glint_err_set(err, GLINT_EINVAL, "visibility of %d points and %d directions",
                             npoints, k);
    for (size_t i = 0; i < (size_t)3 * npoints; i++)
        if (!isfinite(pos[i]) || !isfinite(nrm[i]))
            return glint_err_set(err, GLINT_EINVAL, "point %zu is not finite", i / 3);
    if (nt > npoints)
        nt = npoints > 0 ? npoints : 1;
    for (int t = 0; t < nt; t++)
        jobs[t] = (vjob){v, pos, nrm, dirs, k, (int)((long)npoints * t / nt),
                         (int)((long)npoints * (t + 1) / nt), bits, 0, cancel, &stopped};
    for (int t = 1; t < nt; t++)
        if (pthread_create(&th[t], NULL, vjob_run, &jobs[t])) {
            vjob_run(&jobs[t]);
            th[t] = 0;
        }
    vjob_run(&jobs[0]);
    for (int t = 1; t < nt; t++)
        if (th[t])
            pthread_join(th[t], NULL);
    for (int t = 0; t < nt; t++)
        total += jobs[t].rays;
    if (rays)
        *rays = total;
    if (stopped)
        return glint_cancel_err(err, "casting shadow rays");
    return 0;
}

/* ---- convexity ------------------------------------------------------------------------- */

typedef struct vkey {
    int64_t q[3];
    int idx;
} vkey;

static int vkey_cmp(const void *a, const void *b)
{
    const vkey *x = a, *y = b;
    for (int e = 0; e < 3; e++)
        if (x->q[e] != y->q[e])
            return x->q[e] < y->q[e] ? -1 : 1;
    return x->idx - y->idx;
}

typedef struct edge {
    int a, b;       /* a < b */
    int tri, fwd;   /* fwd: the triangle runs a -> b */
} edge;

static int edge_cmp(const void *x, const void *y)
{
    const edge *p = x, *q = y;
    if (p->a != q->a)
        return p->a - q->a;
    if (p->b != q->b)
        return p->b - q->b;
    return p->tri - q->tri;
}

static int find(int *par, int i)
{
    while (par[i] != i) {
        par[i] = par[par[i]];
        i = par[i];
    }
    return i;
}

/* vis_mesh_convex's answer, worked out; -1 when out of memory. */
static int convex_compute(const mesh *m, double tol)
{
    int nv = m ? m->nverts : 0, nt = m ? m->ntris : 0, ne = 0, ok = 0, ntri = 0;
    double r = 0.0, cell;
    vkey *keys = NULL;
    int *rep = NULL, *par = NULL, *keep = NULL;
    edge *E = NULL;

    if (nv < 4 || nt < 4)
        return 0;
    for (int i = 0; i < nv; i++) {
        const float *p = m->pos + 3 * i;
        double d = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
        r = d > r ? d : r;
    }
    cell = 1e-6 * (r > 0.0 ? r : 1.0);
    keys = malloc((size_t)nv * sizeof *keys);
    rep = malloc((size_t)nv * sizeof *rep);
    E = malloc((size_t)3 * nt * sizeof *E);
    par = malloc((size_t)nt * sizeof *par);
    keep = malloc((size_t)nt * 3 * sizeof *keep);
    if (!keys || !rep || !E || !par || !keep) {
        ok = -1;
        goto done;
    }
    for (int t = 0; t < nt; t++)
        par[t] = t;
    for (int i = 0; i < nv; i++) {
        for (int e = 0; e < 3; e++)
            keys[i].q[e] = (int64_t)llround(m->pos[3 * i + e] / cell);
        keys[i].idx = i;
    }
    qsort(keys, (size_t)nv, sizeof *keys, vkey_cmp);
    for (int i = 0; i < nv; i++) {
        int same = i > 0 && !memcmp(keys[i].q, keys[i - 1].q, sizeof keys[i].q);
        rep[keys[i].idx] = same ? rep[keys[i - 1].idx] : keys[i].idx;
    }
    for (int t = 0; t < nt; t++) {
        int v[3];
        double a[3], b[3], c[3];
        for (int e = 0; e < 3; e++)
            v[e] = rep[m->tri[3 * t + e]];
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (int e = 0; e < 3; e++) {
            a[e] = m->pos[3 * v[1] + e] - m->pos[3 * v[0] + e];
            b[e] = m->pos[3 * v[2] + e] - m->pos[3 * v[0] + e];
        }
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
        if (sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) < 1e-14 * r * r)
            continue;
        for (int e = 0; e < 3; e++)
            keep[3 * t + e] = v[e];
        for (int e = 0; e < 3; e++) {
            int x = v[e], y = v[(e + 1) % 3];
            E[ne++] = (edge){x < y ? x : y, x < y ? y : x, t, x < y};
        }
        ntri++;
    }
    if (ntri < 4)
        goto done;
    qsort(E, (size_t)ne, sizeof *E, edge_cmp);
    for (int i = 0; i < ne; i += 2) {
        const edge *e1 = &E[i], *e2 = &E[i + 1];
        int t1, t2, opp = -1;
        double p0[3], a[3], b[3], nrm[3], nl, d;
        if (i + 1 >= ne || e2->a != e1->a || e2->b != e1->b || e1->fwd == e2->fwd ||
            (i + 2 < ne && E[i + 2].a == e1->a && E[i + 2].b == e1->b))
            goto done; /* open, non-manifold or inconsistently oriented */
        t1 = e1->tri;
        t2 = e2->tri;
        par[find(par, t1)] = find(par, t2);
        for (int e = 0; e < 3; e++)
            if (keep[3 * t2 + e] != e1->a && keep[3 * t2 + e] != e1->b)
                opp = keep[3 * t2 + e];
        for (int e = 0; e < 3; e++) {
            p0[e] = m->pos[3 * keep[3 * t1] + e];
            a[e] = m->pos[3 * keep[3 * t1 + 1] + e] - p0[e];
            b[e] = m->pos[3 * keep[3 * t1 + 2] + e] - p0[e];
        }
        nrm[0] = a[1] * b[2] - a[2] * b[1];
        nrm[1] = a[2] * b[0] - a[0] * b[2];
        nrm[2] = a[0] * b[1] - a[1] * b[0];
        nl = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        d = 0.0;
        for (int e = 0; e < 3; e++)
            d += nrm[e] / nl * (m->pos[3 * opp + e] - p0[e]);
        if (d > tol * r + 1e-7 * r)
            goto done;
    }
    {
        int root = -1;
        for (int t = 0; t < nt; t++) {
            int v0 = rep[m->tri[3 * t]], v1 = rep[m->tri[3 * t + 1]], v2 = rep[m->tri[3 * t + 2]];
            if (v0 == v1 || v1 == v2 || v0 == v2)
                continue;
            if (root < 0)
                root = find(par, t);
            else if (find(par, t) != root)
                goto done;
        }
    }
    ok = 1;
done:
    free(keys);
    free(rep);
    free(E);
    free(par);
    free(keep);
    return ok;
}

/* The answers for the last few meshes, by a hash of their positions and
 * triangles (a mesh is read-only once made, and the same scene's mesh is
 * asked about by every render under an environment: 85 ms for the
 * studio's 131,839-vertex sphere, against 0.5 ms to hash it). */
#define CONVEX_MEMO 8

typedef struct convex_memo {
    uint64_t hash;
    int nverts, ntris, answer;
    double tol;
    unsigned long used; /* 0: empty */
} convex_memo;

static pthread_mutex_t memo_lock = PTHREAD_MUTEX_INITIALIZER;
static convex_memo memo[CONVEX_MEMO];
static unsigned long memo_tick;

static uint64_t mesh_hash(const mesh *m)
{
    XXH3_state_t *st = XXH3_createState();
    uint64_t h;
    if (!st)
        return 0;
    XXH3_64bits_reset(st);
    XXH3_64bits_update(st, m->pos, (size_t)m->nverts * 3 * sizeof *m->pos);
    XXH3_64bits_update(st, m->tri, (size_t)m->ntris * 3 * sizeof *m->tri);
    h = XXH3_64bits_digest(st);
    XXH3_freeState(st);
    return h;
}

int vis_mesh_convex(const mesh *m, double tol)
{
    uint64_t h;
    int answer = -1;
    convex_memo *slot = NULL;
    if (!m || m->nverts < 4 || m->ntris < 4)
        return 0;
    if (!(h = mesh_hash(m)))
        return convex_compute(m, tol) == 1;
    pthread_mutex_lock(&memo_lock);
    for (int i = 0; i < CONVEX_MEMO; i++) {
        convex_memo *c = &memo[i];
        if (c->used && c->hash == h && c->nverts == m->nverts && c->ntris == m->ntris &&
            c->tol == tol) {
            c->used = ++memo_tick;
            answer = c->answer;
        }
    }
    pthread_mutex_unlock(&memo_lock);
    if (answer >= 0)
        return answer;
    if ((answer = convex_compute(m, tol)) < 0)
        return 0; /* out of memory: not known to be convex, and not kept */
    pthread_mutex_lock(&memo_lock);
    for (int i = 0; i < CONVEX_MEMO; i++)
        if (!slot || memo[i].used < slot->used)
            slot = &memo[i];
    *slot = (convex_memo){h, m->nverts, m->ntris, answer, tol, ++memo_tick};
    pthread_mutex_unlock(&memo_lock);
    return answer;
}
