/* err.h: glint's error codes and the error record every fallible call fills.
 *
 * Contract: a fallible function returns 0 on success or one of the negative
 * GLINT_E* codes below.  Where it takes a `glint_err *err`, it also writes a
 * precise, human-readable message there (err may be NULL when the caller does
 * not want the text).  Messages name the offending value and the limit it
 * broke; library messages (LAPACK info, OpenImageIO, EGL) are kept in them.
 * Nothing in core/ aborts on bad input. */
#ifndef GLINT_ERR_H
#define GLINT_ERR_H

enum {
    GLINT_OK = 0,
    GLINT_EINVAL = -1,    /* an argument or input value is invalid */
    GLINT_ENOMEM = -2,    /* allocation failed */
    GLINT_EIO = -3,       /* reading or writing a file failed */
    GLINT_EFORMAT = -4,   /* a file or document is malformed */
    GLINT_ENUMERIC = -5,  /* a numerical routine failed (LAPACK info != 0) */
    GLINT_ERANGE = -6,    /* a size or value is outside the supported range */
    GLINT_ENONFINITE = -7,/* NaN or Inf where finite values are required */
    GLINT_ENOTFOUND = -8, /* a named thing does not exist */
    GLINT_EUNSUPPORTED = -9, /* a valid request this build cannot serve */
    GLINT_EINTERNAL = -10,/* an invariant broke: a bug, reported not aborted */
    /* Access and capacity, raised by the daemon's services: */
    GLINT_EAUTH = -11,    /* credentials missing or not recognized */
    GLINT_EDENIED = -12,  /* credentials recognized, access not granted */
    GLINT_ECONFLICT = -13,/* the request conflicts with the current state */
    GLINT_EBUSY = -14,    /* over capacity right now: try again later */
    GLINT_ETOOBIG = -15,  /* larger than a configured limit */
    GLINT_ECANCELLED = -16/* stopped because its caller asked (cancel.h) */
};

#define GLINT_ERR_MSG_MAX 512
#define GLINT_ERR_KIND_MAX 32

typedef struct glint_err {
    int code;                     /* the last code set (0 if none) */
    char msg[GLINT_ERR_MSG_MAX];  /* NUL-terminated message */
    /* optional finer kind for the API's problem type ("no-paintings");
     * "" unless glint_err_kind() set it after the last glint_err_set() */
    char kind[GLINT_ERR_KIND_MAX];
} glint_err;

/* Set *err (if non-NULL) to `code` with a printf-style message.
 * Returns `code`, so that `return glint_err_set(err, GLINT_EINVAL, ...)`
 * reads naturally. */
int glint_err_set(glint_err *err, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Prefix the existing message of *err with printf-style context, keeping
 * its code ("reading view 3: <old message>").  Returns err->code (or
 * GLINT_EINTERNAL if err is NULL). */
int glint_err_prefix(glint_err *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Name the kind of the error just set (a short slug, [a-z0-9-]); returns
 * err->code.  Accepts NULL. */
int glint_err_kind(glint_err *err, const char *kind);

/* Reset *err to "no error".  Accepts NULL. */
void glint_err_clear(glint_err *err);

/* A short constant name for a code ("invalid argument", ...). */
const char *glint_strerror(int code);

#endif
