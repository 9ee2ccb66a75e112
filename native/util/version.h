// SHGI's version, set by CMake's project() (the single source of truth for it).
#pragma once

namespace shgi {
const char* version();
}
