/* fuzz.h: what every fuzz target shares.
 *
 * A target is one function, LLVMFuzzerTestOneInput, built two ways
 * (tests/fuzz/meson.build): with clang's libFuzzer for a campaign
 * (-Dfuzzing=true, campaign.sh), and with replay.c's main() in every other
 * build, where the test command runs it over the kept corpus and every
 * input that ever crashed (tests/fuzz/corpus/NAME, tests/fuzz/crashes/NAME),
 * under AddressSanitizer and UndefinedBehaviorSanitizer in the sanitizer
 * build.  A target returns 0 for any input; a property it checks (a parse
 * that reads back what it wrote, an offset inside its buffer) aborts with
 * FUZZ_CHECK, which both drivers report as a crash. */
#ifndef GLINT_FUZZ_H
#define GLINT_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

#define FUZZ_CHECK(cond)                                                                \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            fprintf(stderr, "%s:%d: property failed: %s\n", __FILE__, __LINE__, #cond); \
            abort();                                                                    \
        }                                                                               \
    } while (0)

/* With GLINT_FUZZ_VERBOSE set, print why an input was refused (to see
 * what a corpus exercises); silent otherwise. */
void fuzz_note(const char *target, const char *msg);

/* A private directory for the files a target must write (made once,
 * removed at exit); NULL if it cannot be made. */
const char *fuzz_dir(void);

/* Write len bytes to fuzz_dir()/name (replacing it); 0 or -1. */
int fuzz_write(const char *name, const void *data, size_t len);

#endif
