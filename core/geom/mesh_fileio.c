/* mesh_fileio.c: the file system assimp reads through (contract at
 * mio_fs_open in mesh_int.h), and the rules on what a mesh file may refer
 * to.
 *
 * Mesh formats refer to other files: glTF buffers and images, OBJ material
 * libraries (and the textures in them), COLLADA images.  assimp's own file
 * system opens whatever name a file asks for, and its importers join that
 * name to the importing file's directory, or (from memory) to nothing.  So
 * an uploaded glTF whose buffer is "/etc/shadow" would be built from that
 * file's bytes, and a missing file would fail differently from a present
 * one.  glint therefore gives assimp its own file system (assimp's C API:
 * aiImportFileEx with an aiFileIO) and decides every open itself:
 *
 *  - from memory (an upload): the only file that exists is the upload,
 *    under the name mio_fs_name() gives; every other name is refused before
 *    anything touches the file system, so a refusal is the same, in result,
 *    message and time, whether a file of that name exists or not;
 *  - from disk: the mesh file itself, and regular files in its directory or
 *    below it.  A reference that is an absolute path, leaves the directory
 *    through ".." (even to come back: "../sub/x" from sub/), or is a URI
 *    with a scheme other than data: (file://, http://, but also "C:") is
 *    refused.  Names are resolved lexically and
 *    opened in their resolved form ("a/../b" opens "b"); symbolic links
 *    inside the directory are followed (the directory is the caller's).
 *
 * A refused reference fails the load (GLINT_EINVAL, naming the reference,
 * never anything read): an upload that refers to any file assimp needed or
 * to an unsafe name, a disk file that refers to an unsafe name.  An upload
 * that refers to a plain relative file assimp can do without (an OBJ
 * "mtllib model.mtl", a glTF image "tex.png") still loads: nothing is read,
 * and glint uses only the geometry.  Texture paths are checked the same way
 * after the import (assimp records them without opening them), so the rule
 * holds for every reference a file makes, read or not.  data: URIs and a
 * .glb's binary chunk are part of the file and always allowed.
 *
 * assimp wraps every file system in its FileSystemFilter (Importer.cpp),
 * which retries a name it could not open under other spellings: the
 * importing file's directory + the name, the directory + each tail of the
 * name, the name with doubled separators collapsed and %xx decoded.  Each
 * retry comes here and is judged like any other name; a retry that is
 * refused is not reported (the name it derives from already was, or was
 * simply missing).  A retry is recognized by its shape: the directory, a
 * doubled separator, then a piece of a name that already failed.  That
 * recognition only decides what is reported: a retry is resolved and
 * confined to the directory like any other name. */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>

#include "internal/mesh_int.h"

/* Names remembered as failed, for recognizing assimp's retries; past this
 * many, a doubled separator after the directory counts as an absolute
 * reference (refused: the safe side). */
#define MIO_FS_MAX_FAILED 1024

/* Characters of a refused name shown in messages (then "..."). */
#define MIO_REF_SHOWN 60

struct mio_fs {
    struct aiFileIO io;          /* handed to assimp; UserData points here */
    int upload;                  /* 1: from memory */
    const unsigned char *data;   /* the upload (not owned) */
    size_t len;
    char *main;                  /* the name assimp imports */
    size_t dirlen;               /* main[0..dirlen) is its directory, '/' included */
    char **failed;               /* names refused or not found, in order */
    size_t nfailed, capfailed;
    int unsafe_kind;             /* MIO_REF_* of the first unsafe reference, or 0 */
    char unsafe[MIO_REF_SHOWN + 4];  /* that reference, for messages */
    char refused[MIO_REF_SHOWN + 4]; /* upload: the first name refused at all */
};

/* One open file: in memory (data) or on disk (fd). */
typedef struct mio_file {
    struct aiFile f;             /* handed to assimp; UserData points here */
    const unsigned char *data;   /* in memory, or NULL */
    int fd;                      /* on disk, or -1 */
    size_t size, pos;
} mio_file;

/* ------------------------------------------------------------------------ */
/* References                                                                */
/* ------------------------------------------------------------------------ */

int mio_ref_check(const char *ref)
{
    const char *p = ref;
    long depth = 0;

    if (!ref)
        return MIO_REF_ESCAPE;
    if (ref[0] == '/' || ref[0] == '\\')
        return MIO_REF_ABSOLUTE;
    /* RFC 3986 scheme: ALPHA *( ALPHA / DIGIT / "+" / "-" / "." ) ":" */
    if (isalpha((unsigned char)p[0])) {
        p++;
        while (isalnum((unsigned char)*p) || *p == '+' || *p == '-' || *p == '.')
            p++;
        if (*p == ':')
            return strncasecmp(ref, "data:", 5) == 0 ? MIO_REF_DATA : MIO_REF_SCHEME;
    }
    /* ".." components, with '\\' counted as a separator too (the safe side) */
    for (p = ref; *p;) {
        size_t n = strcspn(p, "/\\");
        if (n == 2 && p[0] == '.' && p[1] == '.') {
            if (--depth < 0)
                return MIO_REF_ESCAPE;
        } else if (n && !(n == 1 && p[0] == '.')) {
            depth++;
        }
        p += n;
        if (*p)
            p++;
    }
    return MIO_REF_OK;
}

/* A name as messages show it: printable ASCII only (quotes and
 * backslashes replaced too), at most MIO_REF_SHOWN characters then "...". */
static void mio_ref_show(const char *name, char out[MIO_REF_SHOWN + 4])
{
    size_t i;
    for (i = 0; name[i] && i < MIO_REF_SHOWN; i++) {
        unsigned char c = (unsigned char)name[i];
        out[i] = c < 0x20 || c > 0x7e || c == '"' || c == '\\' ? '?' : (char)c;
    }
    if (name[i])
        memcpy(out + i, "...", 3), i += 3;
    out[i] = '\0';
}

static const char *mio_ref_reason(int kind)
{
    switch (kind) {
    case MIO_REF_ABSOLUTE: return "an absolute path";
    case MIO_REF_ESCAPE: return "a path that leaves its directory through '..'";
    case MIO_REF_SCHEME: return "a URI with a scheme other than data:";
    default: return "a path outside its directory";
    }
}

/* ------------------------------------------------------------------------ */
/* Files                                                                     */
/* ------------------------------------------------------------------------ */

/* Read like assimp's own streams: whole items from memory (MemoryIOStream),
 * as fread does from disk (DefaultIOStream). */
static size_t mio_file_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
    mio_file *mf = (mio_file *)f->UserData;
    size_t want, left, got = 0;

    if (!size || !count || mf->pos >= mf->size)
        return 0;
    left = mf->size - mf->pos;
    if (mf->data) {
        size_t n = left / size < count ? left / size : count;
        memcpy(buf, mf->data + mf->pos, n * size);
        mf->pos += n * size;
        return n;
    }
    want = count > SIZE_MAX / size ? SIZE_MAX : size * count;
    if (want > left)
        want = left;
    while (got < want) {
        ssize_t r = pread(mf->fd, buf + got, want - got, (off_t)(mf->pos + got));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    mf->pos += got;
    return got / size;
}

static size_t mio_file_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
    (void)f, (void)buf, (void)size, (void)count;
    return 0; /* imports never write */
}

static size_t mio_file_tell(struct aiFile *f)
{
    return ((mio_file *)f->UserData)->pos;
}

static size_t mio_file_size(struct aiFile *f)
{
    return ((mio_file *)f->UserData)->size;
}

/* Seek like assimp's own streams: within [0, size] in memory
 * (MemoryIOStream), anywhere from 0 on disk (fseek with a long offset,
 * DefaultIOStream). */
static enum aiReturn mio_file_seek(struct aiFile *f, size_t off, enum aiOrigin origin)
{
    mio_file *mf = (mio_file *)f->UserData;
    if (mf->data) {
        if (origin == aiOrigin_SET && off <= mf->size)
            mf->pos = off;
        else if (origin == aiOrigin_END && off <= mf->size)
            mf->pos = mf->size - off;
        else if (origin == aiOrigin_CUR && off <= mf->size - mf->pos)
            mf->pos += off;
        else
            return aiReturn_FAILURE;
        return aiReturn_SUCCESS;
    }
    {
        long long o = (long long)(long)off, base, to;
        base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? (long long)mf->pos
                                                                   : (long long)mf->size;
        if (origin != aiOrigin_SET && origin != aiOrigin_CUR && origin != aiOrigin_END)
            return aiReturn_FAILURE;
        if ((o > 0 && base > LLONG_MAX - o) || (to = base + o) < 0)
            return aiReturn_FAILURE;
        mf->pos = (size_t)to;
        return aiReturn_SUCCESS;
    }
}

static void mio_file_flush(struct aiFile *f)
{
    (void)f;
}

static mio_file *mio_file_new(void)
{
    mio_file *mf = calloc(1, sizeof *mf);
    if (!mf)
        return NULL;
    mf->f.ReadProc = mio_file_read;
    mf->f.WriteProc = mio_file_write;
    mf->f.TellProc = mio_file_tell;
    mf->f.FileSizeProc = mio_file_size;
    mf->f.SeekProc = mio_file_seek;
    mf->f.FlushProc = mio_file_flush;
    mf->f.UserData = (aiUserData)mf;
    mf->fd = -1;
    return mf;
}

/* A regular file on disk, or NULL (missing, not a regular file, out of
 * memory).  O_NONBLOCK: a FIFO must not block the open. */
static struct aiFile *mio_file_disk(const char *path)
{
    struct stat st;
    mio_file *mf;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0)
        return NULL;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || !(mf = mio_file_new())) {
        close(fd);
        return NULL;
    }
    mf->fd = fd;
    mf->size = (size_t)st.st_size;
    return &mf->f;
}

static void mio_fs_close_proc(struct aiFileIO *io, struct aiFile *f)
{
    mio_file *mf;
    (void)io;
    if (!f)
        return;
    mf = (mio_file *)f->UserData;
    if (mf->fd >= 0)
        close(mf->fd);
    free(mf);
}

/* ------------------------------------------------------------------------ */
/* Deciding an open                                                          */
/* ------------------------------------------------------------------------ */

static void mio_fs_remember(mio_fs *fs, const char *name)
{
    char *copy;
    if (fs->nfailed == MIO_FS_MAX_FAILED)
        return;
    if (fs->nfailed == fs->capfailed) {
        size_t cap = fs->capfailed ? 2 * fs->capfailed : 16;
        char **n = realloc(fs->failed, cap * sizeof *n);
        if (!n)
            return;
        fs->failed = n;
        fs->capfailed = cap;
    }
    if ((copy = strdup(name)))
        fs->failed[fs->nfailed++] = copy;
}

/* Does `t` occur in a name that failed, at its start or right after a
 * separator?  (FileSystemFilter's retries are the directory, a separator,
 * then a piece of the failed name from one of its separators on, cut to
 * the length of its last component: assimp 5.2's substr.) */
static int mio_fs_is_retry(const mio_fs *fs, const char *t)
{
    size_t tl = strlen(t);
    if (!tl)
        return 0;
    for (size_t i = 0; i < fs->nfailed; i++) {
        const char *p = fs->failed[i];
        for (const char *q = strstr(p, t); q; q = strstr(q + 1, t))
            if (q == p || q[-1] == '/' || q[-1] == '\\')
                return 1;
    }
    return 0;
}

/* dir + rel resolved lexically ("." and empty components dropped, ".."
 * applied; rel must not leave dir: mio_ref_check said MIO_REF_OK).  NULL
 * when out of memory. */
static char *mio_fs_resolve(const char *dir, size_t dirlen, const char *rel)
{
    size_t rl = strlen(rel), o = dirlen;
    char *out = malloc(dirlen + rl + 1);
    const char *p = rel;
    if (!out)
        return NULL;
    memcpy(out, dir, dirlen);
    while (*p) {
        size_t n = strcspn(p, "/");
        if (n == 2 && p[0] == '.' && p[1] == '.') {
            /* back to the previous separator, never into dir */
            if (o > dirlen)
                o--;
            while (o > dirlen && out[o - 1] != '/')
                o--;
        } else if (n && !(n == 1 && p[0] == '.')) {
            memcpy(out + o, p, n);
            o += n;
            out[o++] = '/';
        }
        p += n;
        if (*p)
            p++;
    }
    if (o > dirlen && out[o - 1] == '/')
        o--;
    out[o] = '\0';
    return out;
}

/* Every name but the main file's. */
static struct aiFile *mio_fs_open_other(mio_fs *fs, const char *name)
{
    const char *rel = name;
    int outside = 0, retry = 0, kind;
    struct aiFile *f = NULL;

    if (fs->dirlen && strncmp(name, fs->main, fs->dirlen) == 0)
        rel = name + fs->dirlen;
    else if (fs->dirlen)
        outside = 1; /* relative to the working directory, or absolute */
    if (!outside && rel[0] == '/') {
        /* a doubled separator after the directory: an absolute reference
         * an importer joined to it, or assimp retrying a missing file */
        const char *t = rel;
        while (*t == '/')
            t++;
        if (mio_fs_is_retry(fs, t)) {
            rel = t;
            retry = 1;
        }
    }
    kind = mio_ref_check(rel);
    if (!fs->upload && !outside && kind == MIO_REF_OK) {
        char *path = mio_fs_resolve(fs->main, fs->dirlen, rel);
        if (path) {
            f = mio_file_disk(path);
            free(path);
        }
    }
    if (f)
        return f;
    if (!retry && kind != MIO_REF_DATA) {
        if (kind != MIO_REF_OK && !fs->unsafe_kind) {
            fs->unsafe_kind = kind;
            mio_ref_show(rel, fs->unsafe);
        }
        if (fs->upload && !fs->refused[0])
            mio_ref_show(rel, fs->refused);
    }
    mio_fs_remember(fs, name);
    return NULL;
}

static struct aiFile *mio_fs_open_proc(struct aiFileIO *io, const char *name, const char *mode)
{
    mio_fs *fs = (mio_fs *)io->UserData;
    if (!name || !mode || strpbrk(mode, "wa+"))
        return NULL; /* imports only read */
    if (strcmp(name, fs->main) == 0) {
        mio_file *mf;
        if (!fs->upload)
            return mio_file_disk(name);
        if (!(mf = mio_file_new()))
            return NULL;
        mf->data = fs->data;
        mf->size = fs->len;
        return &mf->f;
    }
    return mio_fs_open_other(fs, name);
}

/* ------------------------------------------------------------------------ */
/* The file system of one import                                             */
/* ------------------------------------------------------------------------ */

int mio_fs_open(mio_fs **out, const char *path, const void *data, size_t len, const char *fmt,
                glint_err *err)
{
    mio_fs *fs;
    const char *slash;

    *out = NULL;
    fs = calloc(1, sizeof *fs);
    if (!fs)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening a mesh import");
    fs->io.OpenProc = mio_fs_open_proc;
    fs->io.CloseProc = mio_fs_close_proc;
    fs->io.UserData = (aiUserData)fs;
    if (path) {
        fs->main = strdup(path);
        slash = fs->main ? strrchr(fs->main, '/') : NULL;
        fs->dirlen = slash ? (size_t)(slash - fs->main) + 1 : 0;
    } else {
        /* no directory: importers join references to nothing */
        size_t n = strlen("upload.") + strlen(fmt) + 1;
        fs->upload = 1;
        fs->data = data;
        fs->len = len;
        if ((fs->main = malloc(n)))
            snprintf(fs->main, n, "upload.%s", fmt);
    }
    if (!fs->main) {
        free(fs);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening a mesh import");
    }
    *out = fs;
    return 0;
}

const char *mio_fs_name(const mio_fs *fs)
{
    return fs->main;
}

struct aiFileIO *mio_fs_io(mio_fs *fs)
{
    return &fs->io;
}

static int mio_upload_refuse_shown(const char *shown, const char *what, glint_err *err)
{
    return glint_err_set(err, GLINT_EINVAL,
                         "%s: refers to the external file \"%s\": external references are "
                         "not allowed in uploads (the file must carry all its data itself, "
                         "e.g. glTF buffers as data: URIs, or one .glb)",
                         what, shown);
}

int mio_upload_refuse(const char *ref, const char *what, glint_err *err)
{
    char shown[MIO_REF_SHOWN + 4];
    mio_ref_show(ref, shown);
    return mio_upload_refuse_shown(shown, what, err);
}

static int mio_fs_refuse(const mio_fs *fs, int kind, const char *shown, const char *what,
                         glint_err *err)
{
    if (fs->upload)
        return mio_upload_refuse_shown(shown, what, err);
    return glint_err_set(err, GLINT_EINVAL,
                         "%s: refers to \"%s\", %s: a mesh file may refer only to files in its "
                         "own directory or below it",
                         what, shown, mio_ref_reason(kind));
}

int mio_fs_verdict(const mio_fs *fs, const struct aiScene *sc, const char *what, glint_err *err)
{
    if (fs->unsafe_kind)
        return mio_fs_refuse(fs, fs->unsafe_kind, fs->unsafe, what, err);
    if (sc) {
        /* texture paths: recorded by assimp, never opened */
        for (unsigned m = 0; m < sc->mNumMaterials; m++) {
            const struct aiMaterial *mat = sc->mMaterials[m];
            for (unsigned p = 0; mat && p < mat->mNumProperties; p++) {
                const struct aiMaterialProperty *pr = mat->mProperties[p];
                struct aiString s;
                int kind;
                if (!pr || pr->mType != aiPTI_String ||
                    strcmp(pr->mKey.data, _AI_MATKEY_TEXTURE_BASE) != 0 ||
                    aiGetMaterialString(mat, _AI_MATKEY_TEXTURE_BASE, pr->mSemantic, pr->mIndex,
                                        &s) != aiReturn_SUCCESS ||
                    s.length == 0 || s.data[0] == '*') /* "*N": embedded */
                    continue;
                kind = mio_ref_check(s.data);
                if (kind != MIO_REF_OK && kind != MIO_REF_DATA) {
                    char shown[MIO_REF_SHOWN + 4];
                    mio_ref_show(s.data, shown);
                    return mio_fs_refuse(fs, kind, shown, what, err);
                }
            }
        }
    } else if (fs->upload && fs->refused[0]) {
        /* the import failed, and it asked for a file an upload cannot have */
        return mio_fs_refuse(fs, MIO_REF_OK, fs->refused, what, err);
    }
    return 0;
}

void mio_fs_close(mio_fs *fs)
{
    if (!fs)
        return;
    for (size_t i = 0; i < fs->nfailed; i++)
        free(fs->failed[i]);
    free(fs->failed);
    free(fs->main);
    free(fs);
}
