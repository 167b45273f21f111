/* placeholder */
#include "fitsvc.h"
int fitsvc_open(const char *cache_dir, size_t budget_bytes, int threads, fitsvc **out, glint_err *err) { (void)cache_dir; (void)budget_bytes; (void)threads; (void)err; *out = NULL; return 0; }
void fitsvc_close(fitsvc *f) { (void)f; }
