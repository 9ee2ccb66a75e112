// The machine's memory, for budgets that default to a share of it.
#pragma once

#include <cstdint>

namespace shgi {

// `fraction` of the physical RAM in bytes, or UINT64_MAX (no budget) when the system does not
// say how much there is.
uint64_t physical_memory_share(double fraction);

}  // namespace shgi
