/* Tests of ids and secrets (core/base/ids.h): ids are 32 lowercase hex digits and
 * new ones differ; glint_secret_equal, which every token and key comparison
 * of glintd uses (server/auth.c), is exact at every edge (a difference in
 * the first or the last byte, a prefix, an empty secret, bytes >= 0x80).
 * That its time does not depend on where a guess goes wrong rests on its
 * loop, which has no early exit (core/base/ids.c); no time is measured here. */
#include <string.h>

#include "check.h"
#include "ids.h"

TEST(new_ids_are_valid_and_distinct)
{
    char a[GLINT_ID_LEN], b[GLINT_ID_LEN];
    ASSERT_OK(glint_id_new(a, NULL));
    ASSERT_OK(glint_id_new(b, NULL));
    ASSERT(glint_id_valid(a) && glint_id_valid(b));
    ASSERT(strcmp(a, b) != 0);
    ASSERT(!glint_id_valid(NULL) && !glint_id_valid(""));
    ASSERT(!glint_id_valid("0123456789abcdef0123456789ABCDEF"));
    ASSERT(!glint_id_valid("0123456789abcdef0123456789abcde"));
    ASSERT(!glint_id_valid("0123456789abcdef0123456789abcdef0"));
}

TEST(secret_equal_at_every_edge)
{
    char a[65], b[65];
    memset(a, 'k', 64);
    a[64] = '\0';
    memcpy(b, a, sizeof b);
    ASSERT(glint_secret_equal(a, b));
    for (int i = 0; i < 64; i++) {
        b[i] = 'j';
        ASSERT_MSG(!glint_secret_equal(a, b), "a difference at byte %d went unseen", i);
        b[i] = (char)0xe9;
        ASSERT(!glint_secret_equal(a, b));
        b[i] = 'k';
    }
    b[63] = '\0'; /* a prefix, either way round */
    ASSERT(!glint_secret_equal(a, b) && !glint_secret_equal(b, a));
    ASSERT(glint_secret_equal("", ""));
    ASSERT(!glint_secret_equal("", "x") && !glint_secret_equal("x", ""));
}

TEST(ids_near_share_the_routing_digits_only)
{
    char scene[GLINT_ID_LEN], a[GLINT_ID_LEN], b[GLINT_ID_LEN];
    ASSERT_OK(glint_id_new(scene, NULL));
    ASSERT_OK(glint_id_new_near(scene, a, NULL));
    ASSERT_OK(glint_id_new_near(scene, b, NULL));
    ASSERT(glint_id_valid(a) && glint_id_valid(b));
    ASSERT(memcmp(a, scene, GLINT_ID_ROUTE) == 0 && memcmp(b, scene, GLINT_ID_ROUTE) == 0);
    /* the rest is random: distinct from the scene's and from each other */
    ASSERT(strcmp(a + GLINT_ID_ROUTE, scene + GLINT_ID_ROUTE) != 0);
    ASSERT(strcmp(a + GLINT_ID_ROUTE, b + GLINT_ID_ROUTE) != 0);
    /* no id to be near: an id all the same */
    ASSERT_OK(glint_id_new_near(NULL, a, NULL));
    ASSERT(glint_id_valid(a));
    ASSERT_OK(glint_id_new_near("../etc", a, NULL));
    ASSERT(glint_id_valid(a));
}

TEST_LIST {
    TEST_ENTRY(new_ids_are_valid_and_distinct),
    TEST_ENTRY(secret_equal_at_every_edge),
    TEST_ENTRY(ids_near_share_the_routing_digits_only),
};

TEST_MAIN()
