/* method_registry.c: the methods of every build, in the order GET
 * /api/v1/methods lists them (the first is the default).  Adding a method
 * is one line here (and its core file). */
#include "method_auto.h"
#include "method_auto_env.h"
#include "method_hf2d.h"
#include "method_hf3.h"
#include "method_hf4.h"
#include "method_hybrid.h"
#include "method_maps.h"
#include "method_pbr.h"
#include "method_pbr_detail.h"
#include "method_pbr_env.h"
#include "method_pbr_maps.h"
#include "method_pbr_tab.h"
#include "method_pbr_tab_env.h"
#include "method_srbf.h"
#include "method_tab.h"
#include "method_tab_prior.h"

extern const method *const method_builtin[];

const method *const method_builtin[] = {
    &method_hf3,
    &method_pbr,
    &method_pbr_detail,
    &method_tab,
    &method_tab_prior,
    &method_pbr_tab,
    &method_pbr_maps,
    &method_pbr_env,
    &method_pbr_tab_env,
    &method_srbf,
    &method_hf4,
    &method_hf2d,
    &method_maps,
    &method_hybrid,
    &method_auto,
    &method_auto_env,
    NULL,
};
