/* glr_mesh.c: meshes uploaded to a glr (glr.h, glr_mesh_upload): vertex
 * arrays and index buffer, the bounding sphere the projection's near and
 * far planes come from, and whether the mesh is closed (then back faces
 * can be skipped, see below). */
#include "glr.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "internal/glr_int.h"

#define GLR_MESH_MAGIC 0x676c726dU /* "glrm" */

int glr_mesh_ok(const glr *g, const glr_mesh *m, glint_err *err)
{
    if (!m)
        return glint_err_set(err, GLINT_EINVAL, "mesh is NULL");
    if (m->magic != GLR_MESH_MAGIC || m->owner != g)
        return glint_err_set(err, GLINT_EINVAL,
                             "not a mesh uploaded to this renderer (freed or foreign)");
    return 0;
}

void glr_mesh_free(glr *g, glr_mesh *m)
{
    if (!m)
        return;
    if (g && m->owner == g && m->magic == GLR_MESH_MAGIC && glr_enter(g, NULL) == 0) {
        if (m->vao) {
            glDeleteVertexArrays(1, &m->vao);
            g->st.gl_objects--;
        }
        for (int i = 0; i < 3; i++) {
            if (m->vbo[i]) {
                glDeleteBuffers(1, &m->vbo[i]);
                g->st.gl_objects--;
            }
        }
        if (m->ibo) {
            glDeleteBuffers(1, &m->ibo);
            g->st.gl_objects--;
        }
        g->st.meshes--;
        glr_leave(g);
    }
    m->magic = 0;
    free(m);
}

/* ---- closed meshes: back faces can be skipped ----------------------------
 * A surface that is closed and consistently wound hides every back face
 * behind a front face for an eye outside it (a ray enters before it
 * leaves), also for several such surfaces that intersect.  Drawing only
 * front faces then changes no pixel and halves the triangles llvmpipe
 * sets up.  A mesh qualifies when, after welding vertices with identical
 * positions and skipping triangles with repeated vertices, every directed
 * edge occurs once and its reverse occurs once.  The orientation is the
 * sign of the enclosed volume.  Meshes above GLR_CLOSED_MAX_TRIS are not
 * analysed (drawn with both faces, like any open mesh). */

#define GLR_CLOSED_MAX_TRIS (4 << 20)

typedef struct glr_wv {
    float x, y, z;
    uint32_t i;
} glr_wv;

static int glr_wv_cmp(const void *pa, const void *pb)
{
    const glr_wv *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    if (a->y != b->y)
        return a->y < b->y ? -1 : 1;
    if (a->z != b->z)
        return a->z < b->z ? -1 : 1;
    return 0;
}

static int glr_u64_cmp(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

static int glr_mesh_closed(const mesh *m)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris, ne = 0;
    glr_wv *wv = NULL;
    uint32_t *weld = NULL;
    uint64_t *edges = NULL;
    double vol = 0.0;
    int closed = 0;

    if (nt > GLR_CLOSED_MAX_TRIS)
        return 0;
    wv = malloc(nv * sizeof *wv);
    weld = malloc(nv * sizeof *weld);
    edges = malloc(3 * nt * sizeof *edges);
    if (!wv || !weld || !edges)
        goto done; /* not knowing is fine: draw both faces */
    for (size_t i = 0; i < nv; i++) {
        wv[i].x = m->pos[3 * i];
        wv[i].y = m->pos[3 * i + 1];
        wv[i].z = m->pos[3 * i + 2];
        wv[i].i = (uint32_t)i;
    }
    qsort(wv, nv, sizeof *wv, glr_wv_cmp);
    for (size_t i = 0; i < nv; i++)
        weld[wv[i].i] = i > 0 && glr_wv_cmp(&wv[i], &wv[i - 1]) == 0 ? weld[wv[i - 1].i]
                                                                      : wv[i].i;
    for (size_t t = 0; t < nt; t++) {
        uint32_t v[3];
        const float *p[3];
        for (int k = 0; k < 3; k++) {
            v[k] = weld[m->tri[3 * t + (size_t)k]];
            p[k] = m->pos + 3 * (size_t)v[k];
        }
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
            continue;
        for (int k = 0; k < 3; k++)
            edges[ne++] = (uint64_t)v[k] << 32 | v[(k + 1) % 3];
        vol += (double)p[0][0] * ((double)p[1][1] * p[2][2] - (double)p[1][2] * p[2][1]) -
               (double)p[0][1] * ((double)p[1][0] * p[2][2] - (double)p[1][2] * p[2][0]) +
               (double)p[0][2] * ((double)p[1][0] * p[2][1] - (double)p[1][1] * p[2][0]);
    }
    if (ne == 0)
        goto done;
    qsort(edges, ne, sizeof *edges, glr_u64_cmp);
    for (size_t i = 0; i < ne; i++) {
        uint64_t rev = edges[i] >> 32 | edges[i] << 32;
        if (i > 0 && edges[i] == edges[i - 1])
            goto done; /* an edge used twice the same way: non-manifold or misoriented */
        if (!bsearch(&rev, edges, ne, sizeof *edges, glr_u64_cmp))
            goto done; /* a boundary edge: open */
    }
    /* vol is 6x the signed volume; a flat or tiny closed surface is left alone */
    closed = vol > 1e-9 ? 1 : vol < -1e-9 ? -1 : 0;
done:
    free(wv);
    free(weld);
    free(edges);
    return closed;
}

static int glr_mesh_upload_in(glr *g, const mesh *msh, glr_mesh **out, glint_err *err)
{
    static const int ncomp[3] = {3, 3, 2};
    glr_mesh *m;
    const float *arrays[3];
    double lo[3], hi[3], r2 = 0.0;
    size_t nv;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "glr_mesh_upload: NULL output");
    *out = NULL;
    if (!g)
        return glint_err_set(err, GLINT_EINVAL, "glr_mesh_upload: renderer is NULL");
    rc = mesh_validate(msh, err);
    if (rc)
        return rc;
    if ((size_t)msh->ntris > (size_t)INT32_MAX / 3)
        return glint_err_set(err, GLINT_ERANGE, "mesh of %d triangles too large to draw",
                             msh->ntris);
    rc = glr_enter(g, err);
    if (rc)
        return rc;
    m = calloc(1, sizeof *m);
    if (!m)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a mesh record");
    m->magic = GLR_MESH_MAGIC;
    m->owner = g;
    g->st.meshes++;

    /* Bounding sphere: box centre, farthest vertex. */
    nv = (size_t)msh->nverts;
    for (int c = 0; c < 3; c++)
        lo[c] = hi[c] = msh->pos[c];
    for (size_t i = 0; i < nv; i++)
        for (int c = 0; c < 3; c++) {
            double x = msh->pos[3 * i + c];
            lo[c] = x < lo[c] ? x : lo[c];
            hi[c] = x > hi[c] ? x : hi[c];
        }
    for (int c = 0; c < 3; c++)
        m->center[c] = 0.5 * (lo[c] + hi[c]);
    for (size_t i = 0; i < nv; i++) {
        double d2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double d = msh->pos[3 * i + c] - m->center[c];
            d2 += d * d;
        }
        r2 = d2 > r2 ? d2 : r2;
    }
    m->radius = sqrt(r2);
    m->closed = glr_mesh_closed(msh);
    m->nverts = msh->nverts;

    glr_gl_drain();
    arrays[0] = msh->pos;
    arrays[1] = msh->nrm;
    arrays[2] = msh->uv;
    glGenVertexArrays(1, &m->vao);
    if (m->vao)
        g->st.gl_objects++;
    glBindVertexArray(m->vao);
    for (int a = 0; a < 3; a++) {
        glGenBuffers(1, &m->vbo[a]);
        if (m->vbo[a])
            g->st.gl_objects++;
        glBindBuffer(GL_ARRAY_BUFFER, m->vbo[a]);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nv * (size_t)ncomp[a] * sizeof(float)),
                     arrays[a], GL_STATIC_DRAW);
        glVertexAttribPointer((GLuint)a, ncomp[a], GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray((GLuint)a);
    }
    glGenBuffers(1, &m->ibo);
    if (m->ibo)
        g->st.gl_objects++;
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m->ibo);
    m->nidx = (GLsizei)(3 * (size_t)msh->ntris);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)((size_t)m->nidx * sizeof(uint32_t)),
                 msh->tri, GL_STATIC_DRAW);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    rc = glr_gl_check(err, "uploading a mesh");
    if (rc) {
        glint_err_prefix(err, "mesh of %d vertices, %d triangles", msh->nverts, msh->ntris);
        glr_mesh_free(g, m);
        return rc;
    }
    *out = m;
    return 0;
}

int glr_mesh_upload(glr *g, const mesh *msh, glr_mesh **out, glint_err *err)
{
    int rc = glr_mesh_upload_in(g, msh, out, err);
    glr_leave(g);
    return rc;
}
