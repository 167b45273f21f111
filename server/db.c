/* db.c: db.h on SQLite and on PostgreSQL (libpq).  Each call dispatches on
 * the engine; the PostgreSQL side runs a statement when it is first
 * stepped (PQexecParams, parameters as text) and walks the result's rows. */
#include <errno.h>
#include <libpq-fe.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "db.h"
#include "fsio.h"

#define DB_MAX_PARAMS 9

struct db {
    db_kind kind;
    sqlite3 *lite;
    PGconn *pg;
    int in_tx; /* PostgreSQL: a transaction is open */
};

struct db_stmt {
    db *d;
    sqlite3_stmt *lite;
    /* PostgreSQL */
    char *sql;                        /* with $N */
    char *params[DB_MAX_PARAMS];      /* text or NULL */
    int nparams;
    PGresult *res;
    int row, nrows, ran;
    int oom; /* a binding could not be copied */
    int64_t changes;
};

db_kind db_kind_of(const db *d)
{
    return d->kind;
}

int db_in_tx(const db *d)
{
    return d->kind == DB_SQLITE ? !sqlite3_get_autocommit(d->lite) : d->in_tx;
}

/* ---- errors ----------------------------------------------------------------- */

static int lite_err(db *d, const char *what, glint_err *err)
{
    int code = sqlite3_errcode(d->lite), sys = sqlite3_system_errno(d->lite);
    glint_err_set(err, GLINT_EIO, "database: %s: %s", what, sqlite3_errmsg(d->lite));
    if (code == SQLITE_FULL)
        return glint_err_kind(err, "storage-full");
    if (code == SQLITE_READONLY || code == SQLITE_PERM)
        return glint_err_kind(err, "storage-read-only");
    return fsio_err_kind(err, sys);
}

/* The first line of a libpq message (they end in newlines). */
static void pg_msg(const char *m, char *buf, size_t len)
{
    size_t n;
    snprintf(buf, len, "%s", m && *m ? m : "unknown error");
    n = strcspn(buf, "\n");
    buf[n] = '\0';
}

static int pg_err(db *d, const PGresult *res, const char *what, glint_err *err)
{
    char msg[512];
    const char *state = res ? PQresultErrorField(res, PG_DIAG_SQLSTATE) : NULL;
    pg_msg(res && *PQresultErrorMessage(res) ? PQresultErrorMessage(res) : PQerrorMessage(d->pg),
           msg, sizeof msg);
    glint_err_set(err, GLINT_EIO, "database: %s: %s", what, msg);
    if (PQstatus(d->pg) != CONNECTION_OK)
        return glint_err_kind(err, "database-unavailable");
    if (state && !strcmp(state, "53100"))
        return glint_err_kind(err, "storage-full");
    if (state && !strcmp(state, "25006"))
        return glint_err_kind(err, "storage-read-only");
    return GLINT_EIO;
}

/* Outside a transaction, a connection that has gone down is reopened
 * (a server restart); inside one the transaction is lost anyway. */
static void pg_revive(db *d)
{
    if (PQstatus(d->pg) != CONNECTION_OK && !d->in_tx)
        PQreset(d->pg);
}

/* ---- open, close ---------------------------------------------------------------- */

int db_open_sqlite(const char *path, db **out, glint_err *err)
{
    db *d = calloc(1, sizeof *d);
    *out = NULL;
    if (!d)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening a database");
    d->kind = DB_SQLITE;
    if (sqlite3_open_v2(path, &d->lite,
                        SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                        NULL) != SQLITE_OK) {
        int rc = glint_err_set(err, GLINT_EIO, "cannot open database %s: %s", path,
                               d->lite ? sqlite3_errmsg(d->lite) : "out of memory");
        sqlite3_close(d->lite);
        free(d);
        return rc;
    }
    sqlite3_busy_timeout(d->lite, 10000);
    *out = d;
    return 0;
}

int db_open_postgres(const char *conninfo, db **out, glint_err *err)
{
    db *d = calloc(1, sizeof *d);
    PGresult *res;
    char msg[512];
    int rc;

    *out = NULL;
    if (!d)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening a database");
    d->kind = DB_POSTGRES;
    d->pg = PQconnectdb(conninfo);
    if (!d->pg || PQstatus(d->pg) != CONNECTION_OK) {
        pg_msg(d->pg ? PQerrorMessage(d->pg) : "out of memory", msg, sizeof msg);
        rc = glint_err_set(err, GLINT_EIO, "cannot connect to PostgreSQL: %s", msg);
        glint_err_kind(err, "database-unavailable");
        goto fail;
    }
    /* the store's promise (an answered request is on disk) needs the
     * commit to wait for the WAL flush */
    res = PQexec(d->pg, "SHOW synchronous_commit");
    if (PQresultStatus(res) != PGRES_TUPLES_OK || PQntuples(res) != 1 ||
        !strcmp(PQgetvalue(res, 0, 0), "off")) {
        rc = glint_err_set(err, GLINT_EUNSUPPORTED,
                           "PostgreSQL: synchronous_commit is off: glintd needs commits on "
                           "disk before it answers (set it to on)");
        PQclear(res);
        goto fail;
    }
    PQclear(res);
    res = PQexec(d->pg, "SET client_min_messages = warning");
    PQclear(res);
    *out = d;
    return 0;
fail:
    PQfinish(d->pg);
    free(d);
    return rc;
}

void db_close(db *d)
{
    if (!d)
        return;
    if (d->kind == DB_SQLITE)
        sqlite3_close(d->lite);
    else
        PQfinish(d->pg);
    free(d);
}

/* ---- statements without results ---------------------------------------------------- */

int db_exec(db *d, const char *sql, glint_err *err)
{
    if (d->kind == DB_SQLITE) {
        char *msg = NULL;
        if (sqlite3_exec(d->lite, sql, NULL, NULL, &msg) != SQLITE_OK) {
            int rc = lite_err(d, sql, err);
            sqlite3_free(msg);
            return rc;
        }
        return 0;
    }
    pg_revive(d);
    PGresult *res = PQexec(d->pg, sql);
    ExecStatusType s = PQresultStatus(res);
    int rc = (s == PGRES_COMMAND_OK || s == PGRES_TUPLES_OK) ? 0 : pg_err(d, res, sql, err);
    PQclear(res);
    return rc;
}

int db_begin(db *d, glint_err *err)
{
    int rc;
    if (d->kind == DB_SQLITE)
        return db_exec(d, "BEGIN IMMEDIATE", err);
    if (!(rc = db_exec(d, "BEGIN", err)))
        d->in_tx = 1;
    return rc;
}

int db_begin_read(db *d, glint_err *err)
{
    int rc;
    if (d->kind == DB_SQLITE)
        return db_exec(d, "BEGIN", err);
    if (!(rc = db_exec(d, "BEGIN ISOLATION LEVEL REPEATABLE READ, READ ONLY", err)))
        d->in_tx = 1;
    return rc;
}

int db_commit(db *d, glint_err *err)
{
    int rc = db_exec(d, "COMMIT", err);
    if (d->kind == DB_POSTGRES)
        d->in_tx = 0; /* a failed COMMIT ends the transaction too */
    return rc;
}

void db_rollback(db *d)
{
    if (d->kind == DB_SQLITE) {
        if (!sqlite3_get_autocommit(d->lite))
            sqlite3_exec(d->lite, "ROLLBACK", NULL, NULL, NULL);
        return;
    }
    if (d->in_tx) {
        PQclear(PQexec(d->pg, "ROLLBACK"));
        d->in_tx = 0;
    }
}

/* ---- prepared statements ---------------------------------------------------------------- */

/* ?N -> $N (N one digit, as the store writes them). */
static char *pg_sql(const char *sql, int *nparams)
{
    size_t n = strlen(sql);
    char *out = malloc(n + 1), *o = out;
    *nparams = 0;
    if (!out)
        return NULL;
    for (const char *c = sql; *c; c++) {
        if (*c == '?' && c[1] >= '1' && c[1] <= '9') {
            *o++ = '$';
            if (c[1] - '0' > *nparams)
                *nparams = c[1] - '0';
        } else {
            *o++ = *c;
        }
    }
    *o = '\0';
    return out;
}

db_stmt *db_prep(db *d, const char *sql, glint_err *err)
{
    db_stmt *st = calloc(1, sizeof *st);
    if (!st) {
        glint_err_set(err, GLINT_ENOMEM, "out of memory preparing a statement");
        return NULL;
    }
    st->d = d;
    if (d->kind == DB_SQLITE) {
        if (sqlite3_prepare_v2(d->lite, sql, -1, &st->lite, NULL) != SQLITE_OK) {
            lite_err(d, "prepare", err);
            sqlite3_finalize(st->lite);
            free(st);
            return NULL;
        }
        return st;
    }
    if (!(st->sql = pg_sql(sql, &st->nparams))) {
        free(st);
        glint_err_set(err, GLINT_ENOMEM, "out of memory preparing a statement");
        return NULL;
    }
    return st;
}

static void pg_set(db_stmt *st, int i, char *text, int want)
{
    if (want && !text)
        st->oom = 1;
    if (i < 1 || i > DB_MAX_PARAMS) {
        free(text);
        return;
    }
    free(st->params[i - 1]);
    st->params[i - 1] = text;
    if (i > st->nparams)
        st->nparams = i;
}

void db_bind_text(db_stmt *st, int i, const char *text)
{
    if (st->d->kind == DB_SQLITE) {
        if (text)
            sqlite3_bind_text(st->lite, i, text, -1, SQLITE_TRANSIENT);
        else
            sqlite3_bind_null(st->lite, i);
        return;
    }
    pg_set(st, i, text ? strdup(text) : NULL, text != NULL);
}

void db_bind_int(db_stmt *st, int i, int64_t v)
{
    char buf[24];
    if (st->d->kind == DB_SQLITE) {
        sqlite3_bind_int64(st->lite, i, v);
        return;
    }
    snprintf(buf, sizeof buf, "%lld", (long long)v);
    pg_set(st, i, strdup(buf), 1);
}

void db_bind_null(db_stmt *st, int i)
{
    db_bind_text(st, i, NULL);
}

int db_step(db_stmt *st, const char *what, glint_err *err)
{
    db *d = st->d;
    if (d->kind == DB_SQLITE) {
        int r = sqlite3_step(st->lite);
        if (r == SQLITE_ROW)
            return DB_ROW;
        if (r == SQLITE_DONE) {
            st->changes = sqlite3_changes(d->lite);
            return DB_DONE;
        }
        return lite_err(d, what, err);
    }
    if (st->oom)
        return glint_err_set(err, GLINT_ENOMEM, "database: %s: out of memory", what);
    if (!st->ran) {
        ExecStatusType s;
        pg_revive(d);
        st->res = PQexecParams(d->pg, st->sql, st->nparams, NULL,
                               (const char *const *)st->params, NULL, NULL, 0);
        st->ran = 1;
        st->row = -1;
        s = PQresultStatus(st->res);
        if (s != PGRES_COMMAND_OK && s != PGRES_TUPLES_OK)
            return pg_err(d, st->res, what, err);
        st->nrows = s == PGRES_TUPLES_OK ? PQntuples(st->res) : 0;
        st->changes = strtoll(PQcmdTuples(st->res), NULL, 10);
    }
    if (st->row + 1 < st->nrows) {
        st->row++;
        return DB_ROW;
    }
    st->row = st->nrows;
    return DB_DONE;
}

const char *db_col_text(db_stmt *st, int c)
{
    if (st->d->kind == DB_SQLITE)
        return (const char *)sqlite3_column_text(st->lite, c);
    if (!st->res || st->row < 0 || st->row >= st->nrows || c >= PQnfields(st->res) ||
        PQgetisnull(st->res, st->row, c))
        return NULL;
    return PQgetvalue(st->res, st->row, c);
}

int64_t db_col_int(db_stmt *st, int c)
{
    const char *t;
    if (st->d->kind == DB_SQLITE)
        return sqlite3_column_int64(st->lite, c);
    t = db_col_text(st, c);
    return t ? strtoll(t, NULL, 10) : 0;
}

int db_col_null(db_stmt *st, int c)
{
    if (st->d->kind == DB_SQLITE)
        return sqlite3_column_type(st->lite, c) == SQLITE_NULL;
    return db_col_text(st, c) == NULL;
}

int64_t db_changes(db_stmt *st)
{
    return st->changes;
}

void db_reset(db_stmt *st)
{
    if (st->d->kind == DB_SQLITE) {
        sqlite3_reset(st->lite);
        return;
    }
    PQclear(st->res);
    st->res = NULL;
    st->ran = 0;
    st->row = -1;
    st->nrows = 0;
}

void db_finalize(db_stmt *st)
{
    if (!st)
        return;
    if (st->d->kind == DB_SQLITE) {
        sqlite3_finalize(st->lite);
    } else {
        PQclear(st->res);
        for (int i = 0; i < DB_MAX_PARAMS; i++)
            free(st->params[i]);
        free(st->sql);
    }
    free(st);
}
