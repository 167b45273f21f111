/* Tests of core/fsio's directories: fsio_mkdirs makes every missing level
 * of a path, with one call when the parent is there, and refuses clearly
 * what cannot be a directory. */
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "fsio.h"

static char root[64];

static int setup(void)
{
    if (root[0])
        return 0;
    snprintf(root, sizeof root, "/tmp/glint-fsio-XXXXXX");
    return mkdtemp(root) ? 0 : -1;
}

static int is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* root/rel */
static const char *at(const char *rel)
{
    static char buf[2][512];
    static int k;
    k ^= 1;
    snprintf(buf[k], sizeof buf[k], "%s/%s", root, rel);
    return buf[k];
}

TEST(mkdirs_makes_every_missing_level)
{
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_MSG(fsio_mkdirs(at("a/b/c/d/e"), &e) == 0, "%s", e.msg);
    ASSERT(is_dir(at("a")) && is_dir(at("a/b")) && is_dir(at("a/b/c")) && is_dir(at("a/b/c/d")));
    ASSERT(is_dir(at("a/b/c/d/e")));
    /* there already: fine, and nothing else changes */
    ASSERT_MSG(fsio_mkdirs(at("a/b/c/d/e"), &e) == 0, "%s", e.msg);
    ASSERT_MSG(fsio_mkdirs(at("a/b"), &e) == 0, "%s", e.msg);
    /* one level under a level that is there */
    ASSERT_MSG(fsio_mkdirs(at("a/b/x"), &e) == 0, "%s", e.msg);
    ASSERT(is_dir(at("a/b/x")));
    /* a branch off the middle */
    ASSERT_MSG(fsio_mkdirs(at("a/y/z"), &e) == 0, "%s", e.msg);
    ASSERT(is_dir(at("a/y")) && is_dir(at("a/y/z")));
}

TEST(mkdirs_takes_repeated_and_trailing_slashes)
{
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_MSG(fsio_mkdirs(at("s//t///u/"), &e) == 0, "%s", e.msg);
    ASSERT(is_dir(at("s")) && is_dir(at("s/t")) && is_dir(at("s/t/u")));
    ASSERT_MSG(fsio_mkdirs(at("s/t/u//"), &e) == 0, "%s", e.msg);
    ASSERT_MSG(fsio_mkdirs("/", &e) == 0, "%s", e.msg);
}

TEST(mkdirs_refuses_a_file_in_the_way)
{
    glint_err e;
    FILE *f;
    ASSERT_OK(setup());
    f = fopen(at("file"), "w");
    ASSERT(f != NULL);
    fclose(f);
    /* below a file, at any depth */
    memset(&e, 0, sizeof e);
    ASSERT(fsio_mkdirs(at("file/sub"), &e) != 0);
    ASSERT_MSG(strstr(e.msg, "cannot create directory") && strstr(e.msg, "file"), "%s", e.msg);
    memset(&e, 0, sizeof e);
    ASSERT(fsio_mkdirs(at("file/sub/deeper/still"), &e) != 0);
    ASSERT_MSG(strstr(e.msg, "cannot create directory"), "%s", e.msg);
    ASSERT(!is_dir(at("file/sub")));
}

TEST(mkdirs_refuses_bad_paths)
{
    glint_err e;
    char longp[5000];
    ASSERT_OK(setup());
    memset(&e, 0, sizeof e);
    ASSERT_EQ(fsio_mkdirs("", &e), GLINT_EINVAL);
    ASSERT(e.msg[0] != '\0');
    memset(longp, 'a', sizeof longp - 1);
    longp[sizeof longp - 1] = '\0';
    ASSERT_EQ(fsio_mkdirs(longp, &e), GLINT_EINVAL);
    /* a level name too long for the file system: a clear error, no loop */
    {
        char p[600];
        int n = snprintf(p, sizeof p, "%s/", root);
        memset(p + n, 'n', 300);
        strcpy(p + n + 300, "/below");
        memset(&e, 0, sizeof e);
        ASSERT_EQ(fsio_mkdirs(p, &e), GLINT_EIO);
        ASSERT_MSG(strstr(e.msg, "cannot create directory") && strstr(e.msg, "too long"), "%s",
                   e.msg);
    }
}

TEST(cleanup)
{
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
    ASSERT_EQ(system(cmd), 0);
}

TEST_LIST {
    TEST_ENTRY(mkdirs_makes_every_missing_level),
    TEST_ENTRY(mkdirs_takes_repeated_and_trailing_slashes),
    TEST_ENTRY(mkdirs_refuses_a_file_in_the_way),
    TEST_ENTRY(mkdirs_refuses_bad_paths),
    TEST_ENTRY(cleanup),
};
TEST_MAIN()
