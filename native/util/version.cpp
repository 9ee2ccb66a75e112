#include "util/version.h"

#ifndef SHGI_VERSION
#error "SHGI_VERSION must be defined by the build"
#endif

namespace shgi {
const char* version() { return SHGI_VERSION; }
}  // namespace shgi
