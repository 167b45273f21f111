/* Tests of glint's error records (core/err). */
#include "check.h"
#include "err.h"

TEST(set_and_prefix)
{
    glint_err e;
    glint_err_clear(&e);
    ASSERT_EQ(e.code, 0);
    ASSERT_EQ(glint_err_set(&e, GLINT_ERANGE, "size %d too big", 9), GLINT_ERANGE);
    ASSERT(strcmp(e.msg, "size 9 too big") == 0);
    ASSERT_EQ(glint_err_prefix(&e, "view %d", 3), GLINT_ERANGE);
    ASSERT(strcmp(e.msg, "view 3: size 9 too big") == 0);
    /* NULL records are accepted everywhere */
    ASSERT_EQ(glint_err_set(NULL, GLINT_EIO, "x"), GLINT_EIO);
    glint_err_clear(NULL);
    ASSERT_EQ(glint_err_prefix(NULL, "x"), GLINT_EINTERNAL);
}

TEST(long_messages_truncate_safely)
{
    glint_err e;
    char big[2000];
    memset(big, 'a', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    glint_err_set(&e, GLINT_EINVAL, "%s", big);
    ASSERT_EQ(strlen(e.msg), GLINT_ERR_MSG_MAX - 1);
    glint_err_prefix(&e, "%s", big);
    ASSERT_EQ(strlen(e.msg), GLINT_ERR_MSG_MAX - 1);
}

TEST(names)
{
    ASSERT(strcmp(glint_strerror(GLINT_ENONFINITE), "non-finite value") == 0);
    ASSERT(strcmp(glint_strerror(-999), "unknown error") == 0);
    ASSERT(strcmp(glint_strerror(0), "ok") == 0);
}

TEST_LIST {
    TEST_ENTRY(set_and_prefix),
    TEST_ENTRY(long_messages_truncate_safely),
    TEST_ENTRY(names),
};
TEST_MAIN()
