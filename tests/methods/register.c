/* register.c: the methods a test build adds to the registry (method.c reads
 * method_extra when a program defines it). */
#include "method.h"

extern const method method_lambert_test;
extern const method *const method_extra[];

const method *const method_extra[] = {&method_lambert_test, NULL};
