/* env_cache.c: environments compressed into lights, kept for the next use
 * of the same map at the same settings (env.h, env_prepare).
 *
 * Reading a map and cutting it into lights takes tens of milliseconds (the
 * built-in sky: 44 ms to draw at 512 x 256, 22 ms to cut into 256 lights)
 * and every base render, preview and fit under an environment needs them.
 * A handful of results are kept, the least recently used dropped first,
 * within ENV_CACHE_BYTES; callers get copies (the map's 1.5 MB at 512 x
 * 256 copies in well under a millisecond), so nothing handed out is shared
 * or needs releasing.  An entry is found by the map's identity
 * (env_identity: a file's device, inode, size and modification time, so a
 * map rewritten on disk is read again), the spec, the cut, k, psi and the
 * intensity (the two numbers exactly, as hexadecimal floats).  Thread-safe:
 * one mutex, held only to look up, copy out and insert; the reading and
 * cutting run outside it (two threads asking for the same new entry both
 * compute it, and the second's result is dropped). */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "env.h"

#define ENV_CACHE_N 6
#define ENV_CACHE_BYTES ((size_t)48 << 20)

typedef struct slot {
    char key[4352 + ENV_NAME_MAX + 96];
    env_map map;
    env_lights lights;
    size_t bytes;
    unsigned long used; /* the tick of its last use; 0: empty */
} slot;

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static slot slots[ENV_CACHE_N];
static unsigned long tick;

static size_t map_bytes(const env_map *m)
{
    return (size_t)m->width * m->height * 3 * sizeof(float);
}

static size_t slot_bytes(const env_map *m, const env_lights *l)
{
    return map_bytes(m) + (size_t)l->k * 6 * sizeof(double);
}

/* Deep copies (OUT: m, l); GLINT_ENOMEM leaves both empty. */
static int copy_out(const env_map *sm, const env_lights *sl, env_map *m, env_lights *l,
                    glint_err *err)
{
    *m = *sm;
    *l = *sl;
    m->rgb = malloc(map_bytes(sm));
    l->dir = malloc((size_t)sl->k * 3 * sizeof(double));
    l->power = malloc((size_t)sl->k * 3 * sizeof(double));
    if (!m->rgb || !l->dir || !l->power) {
        env_map_free(m);
        env_lights_free(l);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the environment '%s'",
                             sm->name);
    }
    memcpy(m->rgb, sm->rgb, map_bytes(sm));
    memcpy(l->dir, sl->dir, (size_t)sl->k * 3 * sizeof(double));
    memcpy(l->power, sl->power, (size_t)sl->k * 3 * sizeof(double));
    return 0;
}

static void slot_clear(slot *s)
{
    env_map_free(&s->map);
    env_lights_free(&s->lights);
    memset(s, 0, sizeof *s);
}

/* The slot holding key, or NULL (lock held). */
static slot *find(const char *key)
{
    for (int i = 0; i < ENV_CACHE_N; i++)
        if (slots[i].used && !strcmp(slots[i].key, key))
            return &slots[i];
    return NULL;
}

/* Keep map and lights (moved in) under key, evicting the least recently
 * used until they fit (lock held); they are freed when they cannot be kept. */
static void keep(const char *key, env_map *map, env_lights *lights)
{
    size_t bytes = slot_bytes(map, lights);
    slot *dst = NULL;
    if (bytes > ENV_CACHE_BYTES || find(key)) {
        env_map_free(map);
        env_lights_free(lights);
        return;
    }
    for (;;) {
        slot *old = NULL;
        size_t total = 0;
        dst = NULL;
        for (int i = 0; i < ENV_CACHE_N; i++) {
            total += slots[i].bytes;
            if (!slots[i].used)
                dst = dst ? dst : &slots[i];
            else if (!old || slots[i].used < old->used)
                old = &slots[i];
        }
        if (dst && total + bytes <= ENV_CACHE_BYTES)
            break;
        slot_clear(old); /* something is kept: total > 0 or no free slot */
    }
    snprintf(dst->key, sizeof dst->key, "%s", key);
    dst->map = *map;
    dst->lights = *lights;
    dst->bytes = bytes;
    dst->used = ++tick;
}

int env_prepare(const char *spec, env_cut how, int k, double psi, double intensity,
                env_map *map, env_lights *lights, glint_err *err)
{
    char id[4352], key[sizeof slots[0].key];
    env_map m;
    env_lights l;
    slot *s;
    int rc;

    memset(map, 0, sizeof *map);
    memset(lights, 0, sizeof *lights);
    if ((rc = env_identity(spec, id, sizeof id, err)))
        return rc;
    snprintf(key, sizeof key, "%s|%s|%d|%d|%a|%a", id, spec, (int)how, k, psi, intensity);
    pthread_mutex_lock(&lock);
    if ((s = find(key))) {
        s->used = ++tick;
        rc = copy_out(&s->map, &s->lights, map, lights, err);
        pthread_mutex_unlock(&lock);
        return rc;
    }
    pthread_mutex_unlock(&lock);
    if ((rc = env_resolve(spec, &m, err)))
        return rc;
    if ((rc = env_compress(&m, how, k, psi, intensity, &l, err))) {
        env_map_free(&m);
        return rc;
    }
    if ((rc = copy_out(&m, &l, map, lights, err))) {
        env_map_free(&m);
        env_lights_free(&l);
        return rc;
    }
    pthread_mutex_lock(&lock);
    keep(key, &m, &l);
    pthread_mutex_unlock(&lock);
    return 0;
}

void env_cache_clear(void)
{
    pthread_mutex_lock(&lock);
    for (int i = 0; i < ENV_CACHE_N; i++)
        slot_clear(&slots[i]);
    pthread_mutex_unlock(&lock);
}
