// The machine's memory, for budgets that default to a share of it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace shgi {

// `fraction` of the physical RAM in bytes, or UINT64_MAX (no budget) when the system does not
// say how much there is.
uint64_t physical_memory_share(double fraction);

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with huge pages
// (transparent huge pages in "madvise" mode): a buffer of hundreds of MB then takes ~500 times
// fewer page faults to fill and is freed that much faster. A hint; ignored where unsupported.
void advise_huge_pages(void* data, size_t bytes);

}  // namespace shgi
