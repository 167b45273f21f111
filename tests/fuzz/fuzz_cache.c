/* fuzz_cache.c: the cache files glint reads back from its data directory
 * (data/cache): a file may be torn by a crash, damaged on disk, or placed
 * there by someone else.  The first byte picks the reader:
 *   bits 0-1  0 hf3's decomposition (pcache_decomp_load),
 *             1 the sampling pattern (pattern_load; bit 2: the rule),
 *             2 srbf's energy level, 3 srbf's transfer level;
 *   bit 7     sealed: the rest is the file's body, and the target adds the
 *             magic, kind and a valid checksum around it, so that the fuzzer
 *             reaches the checks behind the checksum (a file with a good
 *             checksum and bad contents can only be written on purpose, but
 *             must not crash glintd either).
 * Without bit 7 the rest is the whole file as found on disk.  The pattern
 * is checked against a small built-in scene (a sphere, 8 x 8, ico12).
 *
 * Seeds: GLINT_FUZZ_SEEDS=DIR fuzz_cache writes that scene's real cache
 * files (both patterns, an hf3 decomposition at res 8) to DIR at start;
 * tests/fuzz/make_seeds.sh turns them into corpus inputs. */
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "fuzz.h"
#include "hf.h"
#include "method_srbf.h"
#include "pattern.h"
#include "pcache.h"
#include "samples.h"
#include "scene.h"

static scene sc;
static char sc_hash[33];
static unsigned char use_all[SCENE_MAX_VIEWS];
static int have_scene;

static void write_seeds(const char *dir)
{
    glint_err e;
    for (int rule = 0; rule < 2; rule++) {
        pattern_in in = {&sc, use_all, rule, sc_hash, 0, 1, NULL, NULL};
        samples s;
        char key[64];
        memset(&s, 0, sizeof s);
        snprintf(key, sizeof key, "fuzz-pattern-%d", rule);
        if (pattern_raster(&in, &s, &e) || pattern_save(&s, dir, key, &e)) {
            fprintf(stderr, "fuzz_cache: seeds: %s\n", e.msg);
            exit(1);
        }
        if (rule == SAMPLES_LIT) {
            hf_design d;
            hf_decomp dc;
            int hit;
            if (hf_design_build(&s, 8, &d, &e) ||
                pcache_decomp_get(dir, &d, s.hash, 0.1, HF_ROUTE_EIG,
                                  hf_rcond_default(HF_ROUTE_EIG), &dc, &hit, &e)) {
                fprintf(stderr, "fuzz_cache: seeds: %s\n", e.msg);
                exit(1);
            }
            hf_decomp_free(&dc);
            hf_design_free(&d);
        }
        samples_free(&s);
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    scene_params p;
    glint_err e;
    const char *seeds = getenv("GLINT_FUZZ_SEEDS");
    scene_params_default(&p);
    p.width = p.height = 8;
    p.view_set = SCENE_VIEWS_ICO12;
    if (scene_create(&p, &sc, &e)) {
        fprintf(stderr, "fuzz_cache: %s\n", e.msg);
        return 0;
    }
    scene_hash(&sc, sc_hash);
    memset(use_all, 1, sizeof use_all);
    have_scene = 1;
    if (seeds)
        write_seeds(seeds);
    return 0;
}

/* The file as the reader will find it (malloc'ed; *n its length). */
static unsigned char *assemble(const uint8_t *body, size_t len, int sealed, int pcache,
                               const char *magic, uint32_t kind, size_t *n)
{
    size_t head = pcache ? 8 : 12;
    unsigned char *f;
    uint64_t h;
    if (!sealed) {
        f = malloc(len ? len : 1);
        if (f && len)
            memcpy(f, body, len);
        *n = len;
        return f;
    }
    f = malloc(head + len + 8);
    if (!f)
        return NULL;
    memcpy(f, magic, 8);
    if (!pcache)
        memcpy(f + 8, &kind, 4);
    if (len)
        memcpy(f + head, body, len);
    h = pcache ? XXH3_64bits(f, head + len) : XXH64(f, head + len, 0);
    memcpy(f + head + len, &h, 8);
    *n = head + len + 8;
    return f;
}

static int is_hex(const unsigned char *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!((p[i] >= '0' && p[i] <= '9') || (p[i] >= 'a' && p[i] <= 'f')))
            return 0;
    return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int which, sealed, rule;
    unsigned char *f;
    size_t n;
    glint_err e = {0};

    if (size < 1 || size > (size_t)8 << 20 || !have_scene || !fuzz_dir())
        return 0;
    which = data[0] & 3;
    rule = (data[0] >> 2) & 1;
    sealed = (data[0] & 0x80) != 0;
    switch (which) {
    case 0: { /* hf3's decomposition: <key>.hfd, the key also inside */
        char key[33] = "00000000000000000000000000000000";
        hf_decomp dc;
        if (!(f = assemble(data + 1, size - 1, sealed, 1, "GLINTPC1", 0, &n)))
            return 0;
        if (n >= 48 && is_hex(f + 16, 32))
            memcpy(key, f + 16, 32);
        {
            char name[40];
            snprintf(name, sizeof name, "%s.hfd", key);
            if (fuzz_write(name, f, n) == 0 && pcache_decomp_load(fuzz_dir(), key, &dc, &e) == 0) {
                fuzz_note("cache", "decomposition loaded");
                FUZZ_CHECK(dc.rank >= 1 && dc.rank <= dc.n && dc.s && dc.V);
                hf_decomp_free(&dc);
            } else {
                fuzz_note("cache", e.msg);
            }
        }
        break;
    }
    case 1: { /* the pattern: its key inside, after seven u32 */
        char key[CACHE_KEY_MAX] = "fuzz", name[64];
        uint32_t klen;
        samples s;
        if (!(f = assemble(data + 1, size - 1, sealed, 0, "GLPATT01", 1, &n)))
            return 0;
        if (n >= 40) {
            memcpy(&klen, f + 36, 4);
            if (klen >= 1 && klen < sizeof key && 40 + (size_t)klen <= n &&
                !memchr(f + 40, 0, klen)) {
                memcpy(key, f + 40, klen);
                key[klen] = '\0';
            }
        }
        pattern_file_name(key, name, sizeof name);
        memset(&s, 0, sizeof s);
        if (fuzz_write(name, f, n) == 0 &&
            pattern_load(fuzz_dir(), key, &sc, sc_hash, use_all, rule, &s, &e) == 0) {
            fuzz_note("cache", "pattern loaded");
            FUZZ_CHECK(s.n >= 1);
            samples_free(&s);
        } else {
            fuzz_note("cache", e.msg);
        }
        break;
    }
    case 2: { /* srbf's energy level */
        srbf_energy x;
        if (!(f = assemble(data + 1, size - 1, sealed, 0, "GLSRBF01", 1, &n)))
            return 0;
        if (fuzz_write("fuzz.srbf", f, n) == 0 && srbf_energy_load(fuzz_dir(), "fuzz", &x, &e) == 0) {
            fuzz_note("cache", "energy loaded");
            srbf_energy_clear(&x);
        } else {
            fuzz_note("cache", e.msg);
        }
        break;
    }
    default: { /* srbf's transfer level */
        srbf_transfer_data x;
        if (!(f = assemble(data + 1, size - 1, sealed, 0, "GLSRBF01", 2, &n)))
            return 0;
        if (fuzz_write("fuzz.srbf", f, n) == 0 &&
            srbf_transfer_load(fuzz_dir(), "fuzz", &x, &e) == 0) {
            fuzz_note("cache", "transfer loaded");
            srbf_transfer_clear(&x);
        } else {
            fuzz_note("cache", e.msg);
        }
        break;
    }
    }
    free(f);
    return 0;
}
