/* log.h: glintd's diagnostic lines on stderr.  Every line is one line: control
 * characters and bytes outside printable ASCII are written as \xHH, and any
 * run of 32 or more hex digits (ids and tokens) as {id}, so no message can
 * forge a line or leak a session's id or token.  The request log (http.c)
 * follows the same rules.  Thread-safe (one write per line). */
#ifndef GLINTD_LOG_H
#define GLINTD_LOG_H

/* "glintd: <message>\n", cleaned as above. */
void log_line(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Clean `in` into out (at most len bytes with the NUL). */
void log_clean(const char *in, char *out, size_t len);

/* Paths never shown to clients (the data and web directories, as given and
 * resolved): registered once at startup, before threads start.
 * log_redact_paths() replaces them in a message by "<data>" (answers' details
 * and jobs' errors go through it). */
void log_private_path(const char *path);
void log_redact_paths(char *msg, size_t len);

#endif
