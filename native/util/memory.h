// The machine's memory, for budgets that default to a share of it.
#pragma once

#include <cstdint>

namespace shgi {

// Physical RAM in bytes, or 0 when the system does not say.
uint64_t physical_memory_bytes();

}  // namespace shgi
