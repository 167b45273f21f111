/* ids.h: identifiers and secrets: 128 random bits as 32 lowercase hex
 * digits (getrandom, the kernel's CSPRNG).  Used for every id and token
 * glint hands out (scenes, sessions, materials, jobs, tokens) and for
 * random file names.  Thread-safe. */
#ifndef GLINT_IDS_H
#define GLINT_IDS_H

#include "err.h"

#define GLINT_ID_LEN 33 /* 32 hex digits + NUL */

/* A new id (OUT: id[GLINT_ID_LEN]).  GLINT_EIO if the kernel refuses
 * randomness (the message says why). */
int glint_id_new(char id[GLINT_ID_LEN], glint_err *err);

/* 1 if `s` has the form of an id (exactly 32 lowercase hex digits), else 0.
 * Accepts NULL. */
int glint_id_valid(const char *s);

/* Equality of two NUL-terminated secrets in time that depends only on their
 * lengths (for tokens and keys).  1 if equal. */
int glint_secret_equal(const char *a, const char *b);

#endif
