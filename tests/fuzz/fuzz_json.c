/* fuzz_json.c: the JSON bodies a request carries, parsed as glintd parses
 * them.  The first byte picks the consumer, the rest is the document:
 *   0  a stroke list (POST .../strokes): stroke_list_from_json; what
 *      parses must read back from its canonical JSON to the same strokes,
 *      bit for bit;
 *   1  fit parameters (POST .../fits "params"), for the method the second
 *      byte picks: method_params_from_json; the canonical JSON of what
 *      parsed must parse to the same canonical JSON;
 *   2  a scene document (the API's explicit views, the CLI's scene files):
 *      scene_from_json, "mesh_file" removed (a server never passes one: it
 *      would name a file to read); a scene that parses must read back from
 *      scene_to_json with the same content hash.
 * Every document that parses is also written back by json_text (indent
 * 0-3 from the first byte), which must read back as the same tree, and
 * give json_dumps's text where it holds no real. */
#include <jansson.h>
#include <string.h>

#include "fuzz.h"
#include "json_text.h"
#include "method.h"
#include "scene.h"
#include "stroke.h"

static int same_bits(const double *a, const double *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

static void strokes(const json_t *j)
{
    stroke_limits lim = {64, 512};
    stroke *list = NULL, *back = NULL;
    int n = 0, nb = 0;
    glint_err e;
    json_t *arr;
    if (stroke_list_from_json(j, &lim, &list, &n, &e)) {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("json", e.msg);
        return;
    }
    FUZZ_CHECK(n >= 1 && n <= lim.max_strokes);
    arr = json_array();
    for (int i = 0; i < n; i++) {
        json_t *s = stroke_to_json(&list[i]);
        FUZZ_CHECK(s != NULL);
        json_array_append_new(arr, s);
    }
    /* through text, as a client would send it back */
    {
        char *text = json_dumps(arr, JSON_COMPACT | JSON_REAL_PRECISION(17));
        json_t *again = text ? json_loads(text, 0, NULL) : NULL;
        FUZZ_CHECK(again != NULL);
        FUZZ_CHECK(stroke_list_from_json(again, &lim, &back, &nb, &e) == 0);
        FUZZ_CHECK(nb == n);
        for (int i = 0; i < n; i++) {
            FUZZ_CHECK(back[i].mode == list[i].mode && back[i].npoints == list[i].npoints);
            if (list[i].mode == STROKE_PAINT)
                FUZZ_CHECK(same_bits(back[i].color, list[i].color, 3));
            if (list[i].mode == STROKE_SCALE)
                FUZZ_CHECK(same_bits(&back[i].scale, &list[i].scale, 1));
            FUZZ_CHECK(same_bits(&back[i].diameter, &list[i].diameter, 1));
            FUZZ_CHECK(same_bits(&back[i].kappa, &list[i].kappa, 1));
            FUZZ_CHECK(same_bits(&back[i].opacity, &list[i].opacity, 1));
            FUZZ_CHECK(same_bits(back[i].pts, list[i].pts, 2 * (size_t)list[i].npoints));
            FUZZ_CHECK(strcmp(back[i].tag, list[i].tag) == 0);
        }
        stroke_list_free(back, nb);
        json_decref(again);
        free(text);
    }
    json_decref(arr);
    stroke_list_free(list, n);
}

static void params(const json_t *j, int which)
{
    const method *m = method_at(which % method_count());
    void *p = method_params_new(m), *q = method_params_new(m);
    glint_err e;
    FUZZ_CHECK(p && q);
    if (method_params_from_json(m, p, j, &e) == 0) {
        json_t *c1 = method_params_to_json(m, p), *c2;
        FUZZ_CHECK(c1 != NULL);
        FUZZ_CHECK(method_params_from_json(m, q, c1, &e) == 0);
        c2 = method_params_to_json(m, q);
        FUZZ_CHECK(c2 != NULL && json_equal(c1, c2));
        json_decref(c1);
        json_decref(c2);
    } else {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("json", e.msg);
    }
    free(p);
    free(q);
}

static void scene_doc(json_t *j)
{
    scene a, b;
    glint_err e;
    char *text, *again, ha[33], hb[33];
    if (json_is_object(j))
        json_object_del(j, "mesh_file");
    text = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(17) | JSON_ENCODE_ANY);
    if (!text)
        return;
    if (scene_from_json(text, &a, &e) == 0) {
        again = scene_to_json(&a, &e);
        FUZZ_CHECK(again != NULL);
        FUZZ_CHECK(scene_from_json(again, &b, &e) == 0);
        scene_hash(&a, ha);
        scene_hash(&b, hb);
        FUZZ_CHECK(strcmp(ha, hb) == 0);
        scene_free(&b);
        scene_free(&a);
        free(again);
    } else {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("json", e.msg);
    }
    free(text);
}

static int has_real(const json_t *j)
{
    const char *k;
    json_t *v;
    size_t i;
    if (json_is_real(j))
        return 1;
    if (json_is_object(j))
        json_object_foreach((json_t *)j, k, v) {
            if (has_real(v))
                return 1;
        }
    if (json_is_array(j))
        json_array_foreach(j, i, v) {
            if (has_real(v))
                return 1;
        }
    return 0;
}

/* json_text, glint's writer of manifests, records and responses: its text
 * reads back as the same tree (reals to the bit), and without reals it is
 * json_dumps's text, byte for byte. */
static void written_back(const json_t *j, int indent)
{
    char *text = json_text(j, indent);
    json_t *back;
    FUZZ_CHECK(text != NULL);
    back = json_loads(text, JSON_REJECT_DUPLICATES, NULL);
    FUZZ_CHECK(back != NULL && json_equal(back, (json_t *)j));
    if (!has_real(j)) {
        char *ref = json_dumps(j, indent ? JSON_INDENT(indent) : JSON_COMPACT);
        FUZZ_CHECK(ref != NULL && strcmp(ref, text) == 0);
        free(ref);
    }
    json_decref(back);
    free(text);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    json_t *j;
    int which;
    if (size < 2 || size > 1 << 16)
        return 0;
    which = data[1];
    /* jansson refuses depth > 2048 itself; the parsers see what it accepts */
    j = json_loadb((const char *)data + 2, size - 2, JSON_REJECT_DUPLICATES, NULL);
    if (!j)
        return 0;
    written_back(j, data[0] / 3 % 4);
    switch (data[0] % 3) {
    case 0: strokes(j); break;
    case 1: params(j, which); break;
    default: scene_doc(j); break;
    }
    json_decref(j);
    return 0;
}
