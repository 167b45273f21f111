/* cmd_methods.c: glint methods: the fit methods this glint knows, with
 * their parameters (from each method's own table), as text or as the JSON
 * of GET /api/v1/methods (--json), and the JSON Schema of a method's
 * parameters as proto/schemas keeps it (--schema NAME). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int print_schema(const char *name)
{
    const method *m = method_find(name);
    char list[256], *text;
    json_t *s;
    if (!m) {
        method_names(list, sizeof list);
        return fail(1, "no method '%s' (available: %s)", name, list);
    }
    s = method_params_schema(m);
    text = s ? json_dumps(s, JSON_INDENT(2) | JSON_REAL_PRECISION(17)) : NULL;
    json_decref(s);
    if (!text)
        return fail(1, "out of memory");
    puts(text);
    free(text);
    return 0;
}

int cmd_methods(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--schema") == 0)
        return print_schema(argv[2]);
    if (argc == 2 && strcmp(argv[1], "--json") == 0) {
        json_t *a = json_array(), *doc;
        for (int i = 0; i < method_count(); i++)
            json_array_append_new(a, method_describe(method_at(i)));
        doc = json_pack("{s:o}", "methods", a);
        if (!doc)
            return fail(1, "out of memory");
        print_json(doc);
        json_decref(doc);
        return 0;
    }
    if (argc != 1)
        return fail(1, "usage: glint methods [--json | --schema NAME]");
    for (int i = 0; i < method_count(); i++) {
        const method *m = method_at(i);
        void *def = method_params_new(m);
        printf("%s: %s%s\n", m->name, m->title, i == 0 ? " (the default)" : "");
        if (m->label)
            printf("  %s (%s lighting): %s\n", m->label,
                   m->lighting == METHOD_LIGHT_ENV ? "environment" : "point", m->summary);
        {
            glint_err why;
            if (method_available(m, &why))
                printf("  cannot fit here: %s\n", why.msg);
        }
        for (int k = 0; def && k < m->nparams; k++) {
            const method_param *p = &m->params[k];
            char v[256];
            method_param_format(p, def, v, sizeof v);
            printf("  %-16s %-14s %s (default %s; changes the %s)\n", p->name,
                   p->type == METHOD_PARAM_INT      ? "integer"
                   : p->type == METHOD_PARAM_NUMBER ? "number"
                   : p->type == METHOD_PARAM_ENUM   ? "choice"
                                                    : "text",
                   p->description, v, p->affects);
        }
        free(def);
    }
    return 0;
}
