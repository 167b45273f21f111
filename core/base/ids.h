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

/* Hex digits at the start of an id that route it (GLINT_ID_ROUTE).  A
 * scene's sessions, a session's materials and jobs share their first
 * GLINT_ID_ROUTE digits with it, so a proxy in front of several glintd
 * replicas can send everything of one scene to one replica (consistent
 * hashing on those digits) without a lookup: its cache lives in one place.
 * The other 96 bits are random. */
#define GLINT_ID_ROUTE 8

/* A new id whose first GLINT_ID_ROUTE digits are those of `near` (an id
 * of the scene, session or set it belongs to); plain glint_id_new when
 * near is NULL or not an id. */
int glint_id_new_near(const char *near, char id[GLINT_ID_LEN], glint_err *err);

/* 1 if `s` has the form of an id (exactly 32 lowercase hex digits), else 0.
 * Accepts NULL. */
int glint_id_valid(const char *s);

/* Equality of two NUL-terminated secrets in time that depends only on their
 * lengths (for tokens and keys).  1 if equal. */
int glint_secret_equal(const char *a, const char *b);

#endif
