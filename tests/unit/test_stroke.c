#include "check.h"
TEST(placeholder) { ASSERT(1); }
TEST_LIST { TEST_ENTRY(placeholder) };
TEST_MAIN()
