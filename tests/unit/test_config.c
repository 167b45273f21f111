/* Tests of glintd's settings (server/config.h): every option keeps to its
 * range and its field, the config file refuses what it does not know
 * (unknown or duplicate keys, wrong types, values too long) naming it, and
 * nothing is cut short silently. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "config.h"
#include "fitsvc.h"

static int load(app_config *c, const char *text, glint_err *e)
{
    config_default(c);
    return config_load_text(c, text, strlen(text), "test.json", e);
}

TEST(defaults_are_the_documented_ones)
{
    app_config c;
    config_default(&c);
    ASSERT(strcmp(c.address, "127.0.0.1") == 0);
    ASSERT_EQ(c.port, 8080);
    ASSERT_EQ(c.cache_bytes, (size_t)512 << 20);
    ASSERT_EQ(c.lim.max_body, (size_t)32 << 20);
    ASSERT_EQ(c.lim.max_image_dim, 4096);
    ASSERT(c.api_key[0] == '\0' && c.allow_origin[0] == '\0' && c.demo_session[0] == '\0');
    ASSERT_EQ(c.background_priority, FITSVC_BG_IDLE);
}

TEST(the_background_priority_by_name)
{
    static const struct { const char *name; int level; } ok[] = {
        {"normal", FITSVC_BG_NORMAL}, {"low", FITSVC_BG_LOW}, {"idle", FITSVC_BG_IDLE}};
    static const char *const bad[] = {"", "IDLE", "idle ", "high", "0", "2", "lowest"};
    app_config c, before;
    glint_err e;
    config_default(&c);
    for (size_t i = 0; i < sizeof ok / sizeof *ok; i++) {
        ASSERT_OK(config_apply(&c, "background-priority", ok[i].name, &e));
        ASSERT_EQ(c.background_priority, ok[i].level);
    }
    ASSERT_OK(config_apply(&c, "background-priority", "low", &e));
    before = c;
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        ASSERT_MSG(config_apply(&c, "background-priority", bad[i], &e) == GLINT_EINVAL,
                   "accepted '%s'", bad[i]);
        ASSERT_MSG(strstr(e.msg, "--background-priority") && strstr(e.msg, "idle, low or normal"),
                   "%s", e.msg);
    }
    ASSERT(memcmp(&c, &before, sizeof c) == 0);
    ASSERT_OK(load(&c, "{\"background_priority\": \"normal\"}", &e));
    ASSERT_EQ(c.background_priority, FITSVC_BG_NORMAL);
    ASSERT(load(&c, "{\"background_priority\": 1}", &e) != 0);
    ASSERT(strstr(e.msg, "idle, low or normal"));
}

TEST(every_number_at_its_ends_and_past_them)
{
    static const struct { const char *name; long lo, hi; } opts[] = {
        {"port", 0, 65535}, {"cache-mb", 1, 1L << 20}, {"threads", 1, 64},
        {"work-mb", 64, 1L << 22}, {"work-slots", 1, 1024}, {"work-wait", 0, 3600},
        {"timeout", 1, 3600}, {"max-connections", 1, 100000},
        {"max-connections-per-ip", 1, 100000}, {"max-waiting-per-ip", 1, 1000000},
        {"health-reserve", 0, 1000}, {"header-timeout", 1, 3600},
        {"min-body-rate", 0, 1L << 30}, {"max-body-mb", 1, 4096},
        {"max-image-dim", 8, 16384}, {"max-mesh-tris", 1, 1L << 24},
        {"max-strokes", 1, 1000000}, {"max-stroke-work", 1, 100000}};
    for (size_t i = 0; i < sizeof opts / sizeof *opts; i++) {
        app_config c, before;
        glint_err e;
        char v[32];
        config_default(&c);
        snprintf(v, sizeof v, "%ld", opts[i].lo);
        ASSERT_MSG(config_apply(&c, opts[i].name, v, &e) == 0, "%s %s: %s", opts[i].name, v, e.msg);
        snprintf(v, sizeof v, "%ld", opts[i].hi);
        ASSERT_MSG(config_apply(&c, opts[i].name, v, &e) == 0, "%s %s: %s", opts[i].name, v, e.msg);
        before = c;
        snprintf(v, sizeof v, "%ld", opts[i].hi + 1);
        ASSERT_EQ(config_apply(&c, opts[i].name, v, &e), GLINT_EINVAL);
        ASSERT_MSG(strstr(e.msg, opts[i].name) && strstr(e.msg, v), "%s", e.msg);
        snprintf(v, sizeof v, "%ld", opts[i].lo - 1);
        ASSERT_EQ(config_apply(&c, opts[i].name, v, &e), GLINT_EINVAL);
        ASSERT_EQ(config_apply(&c, opts[i].name, "12abc", &e), GLINT_EINVAL);
        ASSERT_EQ(config_apply(&c, opts[i].name, "", &e), GLINT_EINVAL);
        ASSERT_EQ(config_apply(&c, opts[i].name, "99999999999999999999999", &e), GLINT_EINVAL);
        ASSERT(memcmp(&c, &before, sizeof c) == 0); /* a refused value changes nothing */
    }
}

TEST(the_units_of_sizes)
{
    app_config c;
    config_default(&c);
    ASSERT_OK(config_apply(&c, "cache-mb", "3", NULL));
    ASSERT_EQ(c.cache_bytes, (size_t)3 << 20);
    ASSERT_OK(config_apply(&c, "max-stroke-work", "7", NULL));
    ASSERT_NEAR(c.lim.max_stroke_work, 7e6, 0);
    ASSERT_OK(config_apply(&c, "work-mb", "4194304", NULL)); /* 4 TiB: fits a size_t */
    ASSERT_EQ(c.work_bytes, (size_t)1 << 42);
}

TEST(strings_fit_their_field_or_are_refused)
{
    app_config c;
    glint_err e;
    char big[5000];
    config_default(&c);
    memset(big, 'x', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    ASSERT_EQ(config_apply(&c, "data-dir", big, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "data-dir") && strstr(e.msg, "4999 bytes"));
    ASSERT(strcmp(c.data_dir, "glint-data") == 0);
    big[4095] = '\0';
    ASSERT_OK(config_apply(&c, "data-dir", big, &e));
    ASSERT_EQ(strlen(c.data_dir), 4095);
    big[64] = '\0'; /* 64 bytes: one past the field */
    ASSERT_EQ(config_apply(&c, "address", big, &e), GLINT_EINVAL);
    ASSERT_EQ(config_apply(&c, "nonsense", "1", &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "unknown option 'nonsense'"));
}

TEST(a_file_with_both_spellings_and_every_type)
{
    app_config c;
    glint_err e;
    ASSERT_OK(load(&c, "{\"port\": 9000, \"data_dir\": \"/srv/g\", \"max-strokes\": \"50\","
                       " \"quiet\": true, \"allow_origin\": \"https://a.example\","
                       " \"demo_session\": \"/srv/g/demo-session.json\"}", &e));
    ASSERT_EQ(c.port, 9000);
    ASSERT(strcmp(c.data_dir, "/srv/g") == 0);
    ASSERT_EQ(c.lim.max_strokes, 50);
    ASSERT_EQ(c.quiet, 1);
    ASSERT(strcmp(c.allow_origin, "https://a.example") == 0);
    ASSERT(strcmp(c.demo_session, "/srv/g/demo-session.json") == 0);
}

TEST(a_bad_file_names_what_is_wrong)
{
    static const struct { const char *text, *want; } cases[] = {
        {"{\"port\": 1, \"port\": 2}", "duplicate"},
        {"{\"prot\": 1}", "unknown option 'prot'"},
        {"{\"port\": 1.5}", "'port' must be a string or an integer"},
        {"{\"port\": null}", "'port' must be a string or an integer"},
        {"{\"data_dir\": [\"a\"]}", "'data_dir' must be a string or an integer"},
        {"{\"quiet\": 1}", "'quiet' must be true or false"},
        {"{\"threads\": 0}", "--threads '0'"},
        {"{\"threads\": 9223372036854775807}", "--threads"},
        {"[1, 2]", "expected a JSON object"},
        {"{\"port\": ", "line 1"},
        {"", "line 1"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        app_config c;
        glint_err e;
        ASSERT_MSG(load(&c, cases[i].text, &e) != 0, "accepted: %s", cases[i].text);
        ASSERT_MSG(strstr(e.msg, cases[i].want) && strstr(e.msg, "test.json"),
                   "%s: '%s' does not say '%s'", cases[i].text, e.msg, cases[i].want);
    }
}

TEST(a_key_of_any_length_is_refused_cleanly)
{
    app_config c;
    glint_err e;
    char text[400];
    snprintf(text, sizeof text, "{\"%0300d\": 1}", 7);
    ASSERT(load(&c, text, &e) != 0);
    ASSERT(strstr(e.msg, "unknown key"));
}

TEST(a_file_too_big_or_missing)
{
    app_config c;
    glint_err e;
    char path[] = "/tmp/glint-config-XXXXXX";
    int fd = mkstemp(path);
    FILE *f;
    ASSERT(fd >= 0);
    f = fdopen(fd, "w");
    fputs("{\"address\": \"", f);
    for (size_t i = 0; i < CONFIG_MAX_FILE; i++)
        fputc('a', f);
    fputs("\"}", f);
    fclose(f);
    config_default(&c);
    ASSERT(config_load_file(&c, path, &e) != 0);
    ASSERT_MSG(strstr(e.msg, "config"), "%s", e.msg);
    unlink(path);
    ASSERT(config_load_file(&c, path, &e) != 0);
    ASSERT(strstr(e.msg, path));
}

TEST_LIST {
    TEST_ENTRY(defaults_are_the_documented_ones),
    TEST_ENTRY(the_background_priority_by_name),
    TEST_ENTRY(every_number_at_its_ends_and_past_them),
    TEST_ENTRY(the_units_of_sizes),
    TEST_ENTRY(strings_fit_their_field_or_are_refused),
    TEST_ENTRY(a_file_with_both_spellings_and_every_type),
    TEST_ENTRY(a_bad_file_names_what_is_wrong),
    TEST_ENTRY(a_key_of_any_length_is_refused_cleanly),
    TEST_ENTRY(a_file_too_big_or_missing),
};

TEST_MAIN()
