// Moved to the public include/atmo/gl/context.h; kept so that #include "gl/context.h" still works.
#pragma once
#include "atmo/gl/context.h"
