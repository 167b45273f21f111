/* placeholder */
#include "auth.h"
