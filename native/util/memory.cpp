#include "util/memory.h"

#include <unistd.h>

#include <limits>

namespace shgi {

uint64_t physical_memory_share(double fraction) {
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return std::numeric_limits<uint64_t>::max();
    return uint64_t(double(pages) * double(page_size) * fraction);
}

}  // namespace shgi
