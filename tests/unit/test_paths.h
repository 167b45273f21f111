#ifndef GLINT_TEST_PATHS_H
#define GLINT_TEST_PATHS_H

/* The source tree and the build tree the test programs were built from
 * (tests/unit/test_paths.c.in; absolute paths). */
extern const char glint_test_source_dir[];
extern const char glint_test_build_dir[];

#endif
