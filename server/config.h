/* config.h: glintd's settings, from the command line and the config file.
 *
 * The config file is a JSON object whose keys are the long options with
 * '_' or '-' ("data_dir" or "data-dir"), values strings or integers (and
 * "quiet" a boolean), e.g. {"port": 8080, "data_dir": "/var/lib/glint"}.
 * Every value is checked as its option is (a number's range, a path's
 * length); an unknown key, a duplicate key or a value of the wrong type is
 * an error naming it: nothing is ignored or cut short silently.
 *
 * Thread-safety: none needed (called before the daemon starts). */
#ifndef GLINT_CONFIG_H
#define GLINT_CONFIG_H

#include <stddef.h>

#include "app.h"
#include "err.h"

/* Largest config file read (bytes). */
#define CONFIG_MAX_FILE ((size_t)1 << 20)

/* The defaults (those glintd --help lists). */
void config_default(app_config *c);

/* Apply one option by its long name ("port", "data-dir") to *c.
 * GLINT_EINVAL naming the option and the value when it is unknown, out of
 * range or too long; *c is unchanged then. */
int config_apply(app_config *c, const char *name, const char *val, glint_err *err);

/* Apply a config file's text (len bytes; `origin` names it in messages).
 * On failure some earlier keys may have been applied: glintd then exits. */
int config_load_text(app_config *c, const char *text, size_t len, const char *origin,
                     glint_err *err);

/* The same from a file (at most CONFIG_MAX_FILE bytes). */
int config_load_file(app_config *c, const char *path, glint_err *err);

#endif
