/* store_pixels.c: a painting's decoded pixels kept beside its blob (store.h,
 * "Decoded paintings").
 *
 * The file is "<blob>.px" (img_raw.h), written after the painting's commit
 * and never before it, so it always belongs to a blob some row named.  It
 * goes when its blob goes: a replacement removes the old blob and its
 * pixels (store_log.c), a session's deletion its whole directory, and the
 * sweep at open the pixels of blobs no row names (a crash between a
 * replacement's commit and its removals). */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "img_raw.h"
#include "store_int.h"

/* The blob of (session, view) now, and its version. */
static int current_blob(store *s, const char *session, int view, int64_t *version, char *blob,
                        size_t len, glint_err *err)
{
    int rc;
    pthread_mutex_lock(&s->lock);
    rc = store_painting_row(s, session, view, version, blob, len, err);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

/* The pixels file of a blob, split for img_raw (OUT: dir, name). */
static int pixels_path(store *s, const char *blob, char *dir, size_t dlen, char *name,
                       size_t nlen, glint_err *err)
{
    char px[600], *slash;
    int rc;
    if (snprintf(px, sizeof px, "%s" STORE_PIXELS_SUFFIX, blob) >= (int)sizeof px)
        return glint_err_set(err, GLINT_EINVAL, "a painting's blob name is too long");
    if ((rc = store_blob_path(s, px, dir, dlen, err)))
        return rc;
    slash = strrchr(dir, '/');
    if (!slash || snprintf(name, nlen, "%s", slash + 1) >= (int)nlen)
        return glint_err_set(err, GLINT_EINVAL, "a painting's blob name is too long");
    *slash = '\0';
    return 0;
}

int store_painting_pixels_put(store *s, const char *session, int view, int64_t version,
                              const img *im, glint_err *err)
{
    char blob[STORE_BLOB_NAME_MAX], dir[STORE_PATH_MAX], name[600];
    int64_t now = 0;
    int rc;

    if ((rc = current_blob(s, session, view, &now, blob, sizeof blob, err)))
        return rc;
    if (now != version)
        return glint_err_set(err, GLINT_ECONFLICT, "view %d is at painting version %lld, "
                             "not %lld", view, (long long)now, (long long)version);
    if ((rc = pixels_path(s, blob, dir, sizeof dir, name, sizeof name, err)) ||
        (rc = img_raw_save(im, dir, name, err)))
        return rc;
    /* a replacement committed meanwhile removed the blob, perhaps before
     * this file was there: remove what it could not */
    if (current_blob(s, session, view, &now, blob, sizeof blob, NULL) != 0 || now != version) {
        char path[STORE_PATH_MAX + 608];
        snprintf(path, sizeof path, "%s/%s", dir, name);
        unlink(path);
        return glint_err_set(err, GLINT_ECONFLICT, "view %d was painted again meanwhile", view);
    }
    return 0;
}

int store_painting_pixels_get(store *s, const char *session, int view, int max_dim, img *out,
                              int64_t *version, glint_err *err)
{
    char blob[STORE_BLOB_NAME_MAX], dir[STORE_PATH_MAX], name[600];
    int rc;

    memset(out, 0, sizeof *out);
    /* no lock held while reading: a replacement may remove the file after
     * its name was read (GLINT_ENOTFOUND; the caller reads the blob), or
     * leave the pixels of the version named, which is what *version says */
    if ((rc = current_blob(s, session, view, version, blob, sizeof blob, err)) ||
        (rc = pixels_path(s, blob, dir, sizeof dir, name, sizeof name, err)))
        return rc;
    return img_raw_load(dir, name, max_dim, out, err);
}

void store_pixels_delete(store *s, const char *blob)
{
    char px[600];
    if (snprintf(px, sizeof px, "%s" STORE_PIXELS_SUFFIX, blob) < (int)sizeof px)
        store_blob_delete(s, px, NULL);
}
