/* db.h: the SQL engine under glintd's store, SQLite or PostgreSQL, behind
 * one small interface (prepare, bind, step, read a column), so the store's
 * logic (store.c, store_log.c) is written once and runs on both.
 *
 * Conventions:
 *   - SQL text uses SQLite's numbered parameters ?1 .. ?9; the PostgreSQL
 *     backend rewrites them to $1 .. $9 (a '?' inside a quoted literal is
 *     never used by the store and is not special-cased).  Everything else
 *     the store sends is SQL both engines accept (INSERT ... ON CONFLICT,
 *     UPDATE ... RETURNING), except the few statements chosen by db_kind_of().
 *   - Values are bound as text or 64-bit integers (or NULL) and read back
 *     as text or integers; PostgreSQL infers each parameter's type from
 *     where it is used.
 *   - Transactions: db_begin() opens a write transaction (SQLite: BEGIN
 *     IMMEDIATE, the database's write lock up front; PostgreSQL: BEGIN at
 *     READ COMMITTED, with rows locked by the statements that need them),
 *     db_begin_read() a read transaction that sees one snapshot (SQLite:
 *     BEGIN; PostgreSQL: REPEATABLE READ, READ ONLY).
 *   - Durability: SQLite in WAL mode with synchronous=FULL; PostgreSQL with
 *     synchronous_commit on (checked at open: a server configured to answer
 *     before the commit is on disk is refused).  A db_commit() that returns
 *     0 has its transaction on disk.
 *   - Errors: a negative GLINT_E* code with "database: <what>: <engine's
 *     message>" and a kind where it is known: "storage-full" (SQLITE_FULL,
 *     SQLSTATE 53100), "storage-read-only" (SQLITE_READONLY, SQLSTATE
 *     25006), "database-unavailable" (the PostgreSQL connection is down: the
 *     next statement outside a transaction reconnects).
 * Thread-safety: none; the store serializes its use of one db. */
#ifndef GLINTD_DB_H
#define GLINTD_DB_H

#include <stdint.h>

#include "err.h"

typedef struct db db;
typedef struct db_stmt db_stmt;

typedef enum { DB_SQLITE, DB_POSTGRES } db_kind;

enum { DB_DONE = 0, DB_ROW = 1 };

/* SQLite: the database file at `path`, created if absent. */
int db_open_sqlite(const char *path, db **out, glint_err *err);
/* PostgreSQL: a libpq connection string ("host=/run/pg dbname=glint" or
 * "postgresql://user@host:port/db"). */
int db_open_postgres(const char *conninfo, db **out, glint_err *err);
void db_close(db *d);
db_kind db_kind_of(const db *d);

/* Run SQL without parameters or results. */
int db_exec(db *d, const char *sql, glint_err *err);
int db_begin(db *d, glint_err *err);
int db_begin_read(db *d, glint_err *err);
int db_commit(db *d, glint_err *err);
/* Roll back the open transaction, if any (never fails). */
void db_rollback(db *d);
/* Is a transaction open? */
int db_in_tx(const db *d);

/* A statement with parameters ?1..?9 (NULL with *err set). */
db_stmt *db_prep(db *d, const char *sql, glint_err *err);
/* Bind parameter i (from 1).  text NULL binds SQL NULL. */
void db_bind_text(db_stmt *st, int i, const char *text);
void db_bind_int(db_stmt *st, int i, int64_t v);
void db_bind_null(db_stmt *st, int i);
/* The next row: DB_ROW, DB_DONE, or a negative code naming `what`. */
int db_step(db_stmt *st, const char *what, glint_err *err);
/* Columns of the current row (from 0).  text: NULL for SQL NULL; valid
 * until the next db_step/db_reset/db_finalize. */
const char *db_col_text(db_stmt *st, int c);
int64_t db_col_int(db_stmt *st, int c);
int db_col_null(db_stmt *st, int c);
/* Rows changed by the statement's last completed step. */
int64_t db_changes(db_stmt *st);
/* Ready to run again (bindings kept until rebound). */
void db_reset(db_stmt *st);
void db_finalize(db_stmt *st);

#endif
