/* store_blob.c: blob files under data_dir/blobs (store.h). */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fsio.h"
#include "ids.h"
#include "store_int.h"

static int store_blob_name_ok(const char *name)
{
    size_t n;
    if (!name || !*name || name[0] == '/' || strstr(name, "..") || strstr(name, "//"))
        return 0;
    n = strlen(name);
    if (n > 512 || name[n - 1] == '/')
        return 0;
    for (const char *c = name; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
              *c == '.' || *c == '_' || *c == '-' || *c == '/'))
            return 0;
    return 1;
}

int store_blob_path(store *s, const char *name, char *buf, size_t len, glint_err *err)
{
    if (!store_blob_name_ok(name))
        return glint_err_set(err, GLINT_EINVAL, "invalid blob name \"%.80s\"", name ? name : "");
    return fsio_join(buf, len, s->blobs, name, err);
}

static void store_fsync_dir(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
}

/* Make the directory holding `path` (under s->blobs), fsyncing each parent
 * whose entry was created, so a committed row never names a file in a
 * directory that a crash forgot. */
static int store_mkparents(store *s, const char *path, glint_err *err)
{
    char dir[STORE_PATH_MAX];
    size_t base = strlen(s->blobs);
    char *slash;
    struct stat st;

    snprintf(dir, sizeof dir, "%s", path);
    slash = strrchr(dir, '/');
    if (!slash || (size_t)(slash - dir) <= base)
        return 0;
    *slash = '\0';
    if (stat(dir, &st) == 0 && S_ISDIR(st.st_mode))
        return 0;
    /* create each missing component below blobs/, fsync its parent */
    for (char *p = dir + base + 1; ; p++) {
        if (*p == '/' || *p == '\0') {
            char save = *p;
            *p = '\0';
            if (mkdir(dir, 0755) == 0) {
                char *up = strrchr(dir, '/');
                if (up) {
                    *up = '\0';
                    store_fsync_dir(dir);
                    *up = '/';
                }
            } else if (errno != EEXIST) {
                int e = errno;
                *p = save;
                return glint_err_set(err, GLINT_EIO, "cannot create %s: %s", dir, strerror(e));
            }
            *p = save;
            if (save == '\0')
                break;
        }
    }
    return 0;
}

int store_blob_put(store *s, const char *name, const void *data, size_t len, glint_err *err)
{
    char path[STORE_PATH_MAX];
    int rc = store_blob_path(s, name, path, sizeof path, err);
    if (rc || (rc = store_mkparents(s, path, err)))
        return rc;
    return fsio_write_atomic(path, data, len, err);
}

int store_blob_get(store *s, const char *name, void **data, size_t *len, glint_err *err)
{
    char path[STORE_PATH_MAX];
    char *d = NULL;
    int rc = store_blob_path(s, name, path, sizeof path, err);
    *data = NULL;
    if (rc)
        return rc;
    rc = fsio_read_all(path, STORE_BLOB_MAX, &d, len, err);
    if (rc)
        return rc;
    *data = d;
    return 0;
}

int store_blob_delete(store *s, const char *name, glint_err *err)
{
    char path[STORE_PATH_MAX];
    int rc = store_blob_path(s, name, path, sizeof path, err);
    if (rc)
        return rc;
    if (unlink(path) != 0 && errno != ENOENT)
        return glint_err_set(err, GLINT_EIO, "cannot remove %s: %s", path, strerror(errno));
    return 0;
}

/* Remove a directory tree below blobs/ (best effort; two levels suffice
 * for glint's layout but any depth works). */
static void store_rmtree(const char *path)
{
    DIR *d = opendir(path);
    struct dirent *e;
    if (!d) {
        unlink(path);
        return;
    }
    while ((e = readdir(d))) {
        char sub[STORE_PATH_MAX];
        struct stat st;
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        if (snprintf(sub, sizeof sub, "%s/%s", path, e->d_name) >= (int)sizeof sub)
            continue;
        if (lstat(sub, &st) == 0 && S_ISDIR(st.st_mode))
            store_rmtree(sub);
        else
            unlink(sub);
    }
    closedir(d);
    rmdir(path);
}

void store_blob_rmtree(store *s, const char *name)
{
    char path[STORE_PATH_MAX];
    if (store_blob_path(s, name, path, sizeof path, NULL) == 0)
        store_rmtree(path);
}

/* A name with a random part: "<prefix><16 hex><suffix>". */
int store_random_name(char *buf, size_t len, const char *prefix, const char *suffix,
                             glint_err *err)
{
    char id[33];
    int rc = glint_id_new(id, err);
    if (rc)
        return rc;
    id[16] = '\0';
    if (snprintf(buf, len, "%s%s%s", prefix, id, suffix) >= (int)len)
        return glint_err_set(err, GLINT_ERANGE, "blob name too long");
    return 0;
}


static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int store_blob_list(store *s, const char *name, json_t **names, glint_err *err)
{
    char path[STORE_PATH_MAX];
    char **list = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    DIR *d;
    int rc;

    *names = NULL;
    if ((rc = store_blob_path(s, name, path, sizeof path, err)))
        return rc;
    if (!(*names = json_array()))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (!(d = opendir(path)))
        return 0;
    while ((e = readdir(d))) {
        char full[STORE_PATH_MAX + 256];
        struct stat st;
        if (e->d_name[0] == '.')
            continue;
        snprintf(full, sizeof full, "%s/%s", path, e->d_name);
        if (lstat(full, &st) != 0 || !S_ISREG(st.st_mode))
            continue;
        if (n == cap) {
            char **nl = realloc(list, (cap = cap ? 2 * cap : 16) * sizeof *nl);
            if (!nl)
                break;
            list = nl;
        }
        if (!(list[n] = strdup(e->d_name)))
            break;
        n++;
    }
    closedir(d);
    if (n)
        qsort(list, n, sizeof *list, cmp_str);
    for (size_t i = 0; i < n; i++) {
        json_array_append_new(*names, json_string(list[i]));
        free(list[i]);
    }
    free(list);
    return 0;
}

/* ---- removals off the request's path (store_int.h) -------------------------- */

static void *reaper_main(void *arg)
{
    store *s = arg;
    pthread_mutex_lock(&s->reap_lock);
    for (;;) {
        char *name;
        while (s->reap_n == 0 && !s->reap_stop)
            pthread_cond_wait(&s->reap_cond, &s->reap_lock);
        if (s->reap_n == 0)
            break; /* stopped, and everything queued done */
        name = s->reap_q[--s->reap_n];
        s->reap_busy = 1;
        pthread_mutex_unlock(&s->reap_lock);
        store_blob_delete(s, name, NULL);
        store_pixels_delete(s, name);
        free(name);
        pthread_mutex_lock(&s->reap_lock);
        s->reap_busy = 0;
        if (s->reap_n == 0)
            pthread_cond_broadcast(&s->reap_idle);
    }
    pthread_cond_broadcast(&s->reap_idle);
    pthread_mutex_unlock(&s->reap_lock);
    return NULL;
}

void store_reap_init(store *s)
{
    pthread_mutex_init(&s->reap_lock, NULL);
    pthread_cond_init(&s->reap_cond, NULL);
    pthread_cond_init(&s->reap_idle, NULL);
}

void store_remove_later(store *s, const char *blob)
{
    char *name = strdup(blob);
    int queued = 0;
    pthread_mutex_lock(&s->reap_lock);
    if (name && !s->reap_stop) {
        if (!s->reap_on) /* started at the first removal: most stores never replace */
            s->reap_on = pthread_create(&s->reaper, NULL, reaper_main, s) == 0;
        if (s->reap_on && s->reap_n == s->reap_cap) {
            int cap = s->reap_cap ? 2 * s->reap_cap : 16;
            char **q = realloc(s->reap_q, (size_t)cap * sizeof *q);
            if (q) {
                s->reap_q = q;
                s->reap_cap = cap;
            }
        }
        if (s->reap_on && s->reap_n < s->reap_cap) {
            s->reap_q[s->reap_n++] = name;
            queued = 1;
            pthread_cond_signal(&s->reap_cond);
        }
    }
    pthread_mutex_unlock(&s->reap_lock);
    if (!queued) { /* no thread or no memory: here and now */
        store_blob_delete(s, blob, NULL);
        store_pixels_delete(s, blob);
        free(name);
    }
}

void store_reap_wait(store *s)
{
    pthread_mutex_lock(&s->reap_lock);
    while (s->reap_on && (s->reap_n > 0 || s->reap_busy))
        pthread_cond_wait(&s->reap_idle, &s->reap_lock);
    pthread_mutex_unlock(&s->reap_lock);
}

void store_reap_stop(store *s)
{
    int on;
    pthread_mutex_lock(&s->reap_lock);
    s->reap_stop = 1;
    on = s->reap_on;
    pthread_cond_signal(&s->reap_cond);
    pthread_mutex_unlock(&s->reap_lock);
    if (on)
        pthread_join(s->reaper, NULL);
    free(s->reap_q);
    s->reap_q = NULL;
    s->reap_n = s->reap_cap = 0;
    pthread_cond_destroy(&s->reap_cond);
    pthread_cond_destroy(&s->reap_idle);
    pthread_mutex_destroy(&s->reap_lock);
}
