/* fuzz_mesh.c: a mesh upload (POST /api/v1/meshes), loaded as glintd loads
 * it: mesh_load_mem, pre-scan, import, cleaning, normals, uvs.  The first
 * byte picks the format glintd accepts (ply, obj, off, gltf, glb, dae),
 * the rest is the file.  What loads must be a valid mesh: finite unit
 * normals, indices in range, uvs in [0, 1].
 *
 * Under libFuzzer (FUZZ_IN_PROCESS) the import runs in this process, so
 * that the fuzzer sees assimp's coverage; a crash inside assimp then stops
 * the campaign unless it runs with -fork and -ignore_crashes (campaign.sh
 * does).  Replayed by the test command the import runs in its child
 * process, as in glintd: every input that ever crashed assimp must come
 * back as an error. */
#include <math.h>

#include "fuzz.h"
#include "mesh.h"

static const char *const formats[] = {"ply", "obj", "off", "gltf", "glb", "dae"};

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
#ifdef FUZZ_IN_PROCESS
    mesh_import_in_process(1);
#endif
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    mesh m;
    mesh_report rep;
    glint_err e;
    if (size < 1 || size > (size_t)4 << 20)
        return 0;
    if (mesh_load_mem(data + 1, size - 1, formats[data[0] % 6], &m, &rep, &e)) {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("mesh", e.msg);
        return 0;
    }
    FUZZ_CHECK(m.nverts >= 3 && m.ntris >= 1 && m.pos && m.nrm && m.tri);
    for (int i = 0; i < 3 * m.ntris; i++)
        FUZZ_CHECK(m.tri[i] < (uint32_t)m.nverts);
    for (int i = 0; i < m.nverts; i++) {
        const float *p = m.pos + 3 * i, *n = m.nrm + 3 * i;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        FUZZ_CHECK(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]));
        FUZZ_CHECK(fabs(len - 1) < 1e-3);
        if (m.uv)
            FUZZ_CHECK(m.uv[2 * i] >= 0 && m.uv[2 * i] <= 1 && m.uv[2 * i + 1] >= 0 &&
                       m.uv[2 * i + 1] <= 1);
    }
    mesh_free(&m);
    return 0;
}
