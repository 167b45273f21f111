#include "err.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

int glint_err_set(glint_err *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        err->kind[0] = '\0';
    }
    return code;
}

int glint_err_kind(glint_err *err, const char *kind)
{
    if (!err)
        return GLINT_EINTERNAL;
    snprintf(err->kind, sizeof err->kind, "%s", kind ? kind : "");
    return err->code;
}

int glint_err_prefix(glint_err *err, const char *fmt, ...)
{
    char head[GLINT_ERR_MSG_MAX];
    char both[2 * GLINT_ERR_MSG_MAX + 4];
    va_list ap;

    if (!err)
        return GLINT_EINTERNAL;
    va_start(ap, fmt);
    vsnprintf(head, sizeof head, fmt, ap);
    va_end(ap);
    snprintf(both, sizeof both, "%s: %s", head, err->msg);
    memcpy(err->msg, both, sizeof err->msg - 1);
    err->msg[sizeof err->msg - 1] = '\0';
    return err->code ? err->code : GLINT_EINTERNAL;
}

void glint_err_clear(glint_err *err)
{
    if (err) {
        err->code = 0;
        err->msg[0] = '\0';
        err->kind[0] = '\0';
    }
}

const char *glint_strerror(int code)
{
    switch (code) {
    case GLINT_OK: return "ok";
    case GLINT_EINVAL: return "invalid argument";
    case GLINT_ENOMEM: return "out of memory";
    case GLINT_EIO: return "I/O error";
    case GLINT_EFORMAT: return "malformed input";
    case GLINT_ENUMERIC: return "numerical failure";
    case GLINT_ERANGE: return "out of range";
    case GLINT_ENONFINITE: return "non-finite value";
    case GLINT_ENOTFOUND: return "not found";
    case GLINT_EUNSUPPORTED: return "unsupported";
    case GLINT_EINTERNAL: return "internal error";
    case GLINT_EAUTH: return "authentication required";
    case GLINT_EDENIED: return "access denied";
    case GLINT_ECONFLICT: return "conflict";
    case GLINT_EBUSY: return "busy";
    case GLINT_ETOOBIG: return "too large";
    case GLINT_ECANCELLED: return "cancelled";
    default: return "unknown error";
    }
}
