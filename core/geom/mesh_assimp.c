/* mesh_assimp.c: the import itself (step 3 and 4 of loading, see
 * mesh_io.c): assimp reads the file, the raw scene is checked (finite
 * coordinates, no empty faces), triangulated, and every node instance of
 * every mesh is merged into one triangle soup with its node transform.
 * This runs inside the import child process (mesh_child.c). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "internal/mesh_int.h"

/* Maximum depth of an assimp node hierarchy we walk. */
#define MIO_MAX_NODE_DEPTH 1024

/* Row-major 3 x 4 affine transform in double precision. */
typedef struct mio_xf {
    double m[3][4];
} mio_xf;

static mio_xf mio_xf_mul(const mio_xf *a, const struct aiMatrix4x4 *b)
{
    const double B[3][4] = {{b->a1, b->a2, b->a3, b->a4},
                            {b->b1, b->b2, b->b3, b->b4},
                            {b->c1, b->c2, b->c3, b->c4}};
    mio_xf r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) {
            double s = j == 3 ? a->m[i][3] : 0.0;
            for (int k = 0; k < 3; k++)
                s += a->m[i][k] * B[k][j];
            r.m[i][j] = s;
        }
    /* the bottom row of an assimp node transform is (0 0 0 1) for affine
     * transforms; a projective one is treated as affine */
    return r;
}

/* What the walk over the node hierarchy collects. */
typedef struct mio_gather {
    const struct aiScene *sc;
    int fill;                 /* 0: count, 1: copy */
    long long nv, nt;         /* counted / copied so far */
    long long prims;          /* points, lines, polygons left out */
    int all_nrm, all_uv;      /* every instanced triangle mesh has them */
    mesh *out;
    const char *what;
} mio_gather;

static int mio_gather_mesh(mio_gather *g, const struct aiMesh *am, unsigned mi, const mio_xf *x,
                           glint_err *err)
{
    long long ntri = 0;
    double det, cof[3][3];
    const double (*M)[4] = x->m;
    uint32_t base;

    for (unsigned f = 0; f < am->mNumFaces; f++)
        if (am->mFaces[f].mNumIndices == 3)
            ntri++;
    if (!g->fill) {
        g->prims += (long long)am->mNumFaces - ntri;
        if (!ntri)
            return 0;
        g->nv += am->mNumVertices;
        g->nt += ntri;
        g->all_nrm &= am->mNormals != NULL;
        g->all_uv &= am->mTextureCoords[0] != NULL && am->mNumUVComponents[0] >= 2;
        if (g->nt > MESH_MAX_TRIS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d triangles (the limit) after merging its meshes",
                                 g->what, MESH_MAX_TRIS);
        if (g->nv > MESH_MAX_VERTS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d vertices (the limit) after merging its meshes",
                                 g->what, MESH_MAX_VERTS);
        return 0;
    }
    if (!ntri)
        return 0;
    /* cofactor matrix: transforms normals (up to the sign of det) */
    cof[0][0] = M[1][1] * M[2][2] - M[1][2] * M[2][1];
    cof[0][1] = M[1][2] * M[2][0] - M[1][0] * M[2][2];
    cof[0][2] = M[1][0] * M[2][1] - M[1][1] * M[2][0];
    cof[1][0] = M[0][2] * M[2][1] - M[0][1] * M[2][2];
    cof[1][1] = M[0][0] * M[2][2] - M[0][2] * M[2][0];
    cof[1][2] = M[0][1] * M[2][0] - M[0][0] * M[2][1];
    cof[2][0] = M[0][1] * M[1][2] - M[0][2] * M[1][1];
    cof[2][1] = M[0][2] * M[1][0] - M[0][0] * M[1][2];
    cof[2][2] = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    det = M[0][0] * cof[0][0] + M[0][1] * cof[0][1] + M[0][2] * cof[0][2];
    base = (uint32_t)g->nv;
    for (unsigned v = 0; v < am->mNumVertices; v++) {
        const struct aiVector3D *p = &am->mVertices[v];
        float *o = g->out->pos + 3 * (size_t)(g->nv + v);
        for (int i = 0; i < 3; i++) {
            double y = M[i][0] * p->x + M[i][1] * p->y + M[i][2] * p->z + M[i][3];
            o[i] = (float)y;
            if (!isfinite(o[i]))
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "%s: mesh %u vertex %u: coordinate not finite after its "
                                     "node transform (%g)", g->what, mi, v, y);
        }
        if (g->out->nrm) {
            const struct aiVector3D *n = &am->mNormals[v];
            float *on = g->out->nrm + 3 * (size_t)(g->nv + v);
            for (int i = 0; i < 3; i++) {
                double y = cof[i][0] * n->x + cof[i][1] * n->y + cof[i][2] * n->z;
                on[i] = (float)(det < 0 ? -y : y);
            }
        }
        if (g->out->uv) {
            const struct aiVector3D *t = &am->mTextureCoords[0][v];
            g->out->uv[2 * (size_t)(g->nv + v)] = t->x;
            g->out->uv[2 * (size_t)(g->nv + v) + 1] = t->y;
        }
    }
    for (unsigned f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *fc = &am->mFaces[f];
        uint32_t *o;
        if (fc->mNumIndices != 3)
            continue;
        for (int k = 0; k < 3; k++)
            if (fc->mIndices[k] >= am->mNumVertices)
                return glint_err_set(err, GLINT_EFORMAT,
                                     "%s: mesh %u face %u: vertex index %u out of range (%u "
                                     "vertices)", g->what, mi, f, fc->mIndices[k],
                                     am->mNumVertices);
        o = g->out->tri + 3 * (size_t)g->nt;
        o[0] = base + fc->mIndices[0];
        o[1] = base + fc->mIndices[det < 0 ? 2 : 1];
        o[2] = base + fc->mIndices[det < 0 ? 1 : 2];
        g->nt++;
    }
    g->nv += am->mNumVertices;
    return 0;
}

static int mio_gather_node(mio_gather *g, const struct aiNode *nd, const mio_xf *parent,
                           int depth, glint_err *err)
{
    mio_xf x;
    int rc;
    if (depth > MIO_MAX_NODE_DEPTH)
        return glint_err_set(err, GLINT_EFORMAT, "%s: node hierarchy deeper than %d", g->what,
                             MIO_MAX_NODE_DEPTH);
    x = mio_xf_mul(parent, &nd->mTransformation);
    for (unsigned i = 0; i < nd->mNumMeshes; i++) {
        unsigned mi = nd->mMeshes[i];
        if (mi >= g->sc->mNumMeshes || !g->sc->mMeshes[mi])
            return glint_err_set(err, GLINT_EFORMAT, "%s: node refers to mesh %u of %u", g->what,
                                 mi, g->sc->mNumMeshes);
        rc = mio_gather_mesh(g, g->sc->mMeshes[mi], mi, &x, err);
        if (rc)
            return rc;
    }
    for (unsigned i = 0; i < nd->mNumChildren; i++) {
        if (!nd->mChildren[i])
            continue;
        rc = mio_gather_node(g, nd->mChildren[i], &x, depth + 1, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* One pass over the scene: every node instance, or every mesh once with
 * the identity when no node refers to a triangle mesh. */
static int mio_gather_pass(mio_gather *g, int by_nodes, glint_err *err)
{
    static const mio_xf id = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
    if (by_nodes)
        return mio_gather_node(g, g->sc->mRootNode, &id, 0, err);
    for (unsigned i = 0; i < g->sc->mNumMeshes; i++) {
        int rc;
        if (!g->sc->mMeshes[i])
            continue;
        rc = mio_gather_mesh(g, g->sc->mMeshes[i], i, &id, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* Import (path, or data + hint) into the raw merged triangle soup *raw
 * (nrm / uv arrays only when every mesh has them), in this process.  assimp
 * reads through glint's file system (mesh_fileio.c): never aiImportFile or
 * aiImportFileFromMemory, whose file system opens any name a file asks
 * for. */
int mio_import_direct(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err)
{
    const struct aiScene *sc = NULL;
    mio_fs *fs = NULL;
    mio_gather g;
    int rc, by_nodes;

    memset(raw, 0, sizeof *raw);
    rc = mio_fs_open(&fs, path, data, len, hint, err);
    if (rc)
        return rc;
    sc = aiImportFileEx(mio_fs_name(fs), aiProcess_ValidateDataStructure, mio_fs_io(fs));
    rc = mio_fs_verdict(fs, sc, what, err);
    if (rc)
        goto done;
    if (!sc) {
        const char *msg = aiGetErrorString();
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: assimp could not read it: %s", what,
                           msg && *msg ? msg : "(no message)");
        goto done;
    }
    /* Before assimp's own processing: every coordinate finite (its vertex
     * joining sorts them), no empty face (what assimp's readers leave for
     * faces missing from a truncated file), and primitive-type flags that
     * match the faces (its triangulation asserts -- aborts the process --
     * when a mesh flagged as having polygons has none). */
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        struct aiMesh *am = sc->mMeshes[i];
        unsigned types = 0;
        if (!am)
            continue;
        for (unsigned f = 0; f < am->mNumFaces; f++) {
            unsigned n = am->mFaces[f].mNumIndices;
            if (n == 0 || !am->mFaces[f].mIndices) {
                rc = glint_err_set(err, GLINT_EFORMAT,
                                   "%s: mesh %u face %u has no vertex indices (truncated or "
                                   "corrupt data)", what, i, f);
                goto done;
            }
            types |= n == 1 ? aiPrimitiveType_POINT
                            : n == 2 ? aiPrimitiveType_LINE
                                     : n == 3 ? aiPrimitiveType_TRIANGLE : aiPrimitiveType_POLYGON;
        }
        am->mPrimitiveTypes = types;
        for (unsigned v = 0; am->mVertices && v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            if (!isfinite(p->x) || !isfinite(p->y) || !isfinite(p->z)) {
                rc = glint_err_set(err, GLINT_ENONFINITE,
                                   "%s: mesh %u vertex %u has a non-finite coordinate (%g, %g, %g)",
                                   what, i, v, p->x, p->y, p->z);
                goto done;
            }
        }
    }
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_SortByPType);
    if (!sc) { /* assimp released the scene */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: assimp post-processing (triangulation, vertex joining) failed",
                           what);
        goto done;
    }

    memset(&g, 0, sizeof g);
    g.sc = sc;
    g.what = what;
    g.all_nrm = g.all_uv = 1;
    by_nodes = sc->mRootNode != NULL;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && g.nt == 0 && by_nodes) { /* no node instances a triangle mesh */
        memset(&g, 0, sizeof g);
        g.sc = sc;
        g.what = what;
        g.all_nrm = g.all_uv = 1;
        by_nodes = 0;
        rc = mio_gather_pass(&g, 0, err);
    }
    if (rc)
        goto done;
    *prims = g.prims;
    if (g.nt == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: no triangles (%u meshes, %lld other "
                           "primitives)", what, sc->mNumMeshes, g.prims);
        goto done;
    }
    rc = mio_alloc(raw, (size_t)g.nv, (size_t)g.nt, g.all_nrm, g.all_uv, err);
    if (rc)
        goto done;
    g.fill = 1;
    g.out = raw;
    g.nv = g.nt = 0;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && (g.nv != raw->nverts || g.nt != raw->ntris))
        rc = glint_err_set(err, GLINT_EINTERNAL, "%s: mesh merge counted %d/%d, copied %lld/%lld",
                           what, raw->nverts, raw->ntris, g.nv, g.nt);
done:
    if (sc)
        aiReleaseImport(sc);
    mio_fs_close(fs);
    if (rc)
        mesh_free(raw);
    return rc;
}
