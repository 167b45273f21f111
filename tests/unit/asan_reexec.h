/* asan_reexec.h: programs that drive llvmpipe (the EGL renderer) under
 * AddressSanitizer.  Included by every such test; the constructor runs
 * before main, so no test can reach llvmpipe before it. */
#ifndef GLINT_ASAN_REEXEC_H
#define GLINT_ASAN_REEXEC_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
/* AddressSanitizer with fast_unwind_on_malloc=0 (as ./setup.sh runs the
 * sanitizer build) deadlocks inside llvmpipe: LLVM's JIT registers
 * exception frames, libgcc's _Unwind_Find_FDE allocates while holding its
 * lock, and ASan's slow unwinder re-enters _Unwind_Find_FDE from malloc.
 * Re-run this program once with the fast unwinder (leak checking stays on). */
static inline void asan_fast_unwind_reexec(void)
{
    const char *opt = getenv("ASAN_OPTIONS");
    static char env[2048], cmd[8192];
    char *argv[64];
    size_t n = 0;
    int argc = 0;
    FILE *f;

    if (!opt || !strstr(opt, "fast_unwind_on_malloc=0") || getenv("GLINT_GLR_REEXEC"))
        return;
    f = fopen("/proc/self/cmdline", "rb");
    if (!f)
        return;
    n = fread(cmd, 1, sizeof cmd - 1, f);
    fclose(f);
    cmd[n] = '\0';
    for (size_t i = 0; i < n && argc < 63; i += strlen(cmd + i) + 1)
        argv[argc++] = cmd + i;
    argv[argc] = NULL;
    snprintf(env, sizeof env, "%s:fast_unwind_on_malloc=1", opt);
    setenv("ASAN_OPTIONS", env, 1);
    setenv("GLINT_GLR_REEXEC", "1", 1);
    printf("  (re-running with ASAN_OPTIONS=%s: llvmpipe's JIT deadlocks with the slow "
           "unwinder)\n",
           env);
    fflush(stdout);
    execv("/proc/self/exe", argv);
    /* exec failed: carry on (and probably hang, as before) */
}
#else
static inline void asan_fast_unwind_reexec(void) {}
#endif

__attribute__((constructor)) static void asan_reexec_at_start(void)
{
    asan_fast_unwind_reexec();
}

#endif
