#include "util/memory.h"

#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "util/error.h"

namespace shgi {
namespace {

constexpr uint64_t kUnlimited = std::numeric_limits<uint64_t>::max();

uint64_t left(uint64_t limit, uint64_t used) { return limit > used ? limit - used : 0; }

// The first number in a file, or kUnlimited ("max", missing or unreadable).
uint64_t read_number(const std::string& path) {
    std::ifstream in(path);
    std::string word;
    if (!(in >> word) || word == "max") return kUnlimited;
    try {
        size_t used = 0;
        const unsigned long long value = std::stoull(word, &used);
        return used == word.size() ? uint64_t(value) : kUnlimited;
    } catch (const std::exception&) {
        return kUnlimited;
    }
}

// The process's virtual size in bytes (first field of /proc/self/statm, in pages), or 0.
uint64_t virtual_size() {
    std::ifstream in("/proc/self/statm");
    unsigned long long pages = 0;
    if (!(in >> pages)) return 0;
    const long page_size = sysconf(_SC_PAGE_SIZE);
    return page_size > 0 ? uint64_t(pages) * uint64_t(page_size) : 0;
}

uint64_t address_space_left() {
    rlimit limit{};
    if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return kUnlimited;
    return left(uint64_t(limit.rlim_cur), virtual_size());
}

// The process's cgroup path relative to the hierarchy's mount: from /proc/self/cgroup, the
// line "0::<path>" (v2) or the one whose controllers include "memory" (v1).
std::string cgroup_path(bool v2) {
    std::ifstream in("/proc/self/cgroup");
    std::string line;
    while (std::getline(in, line)) {
        const size_t first = line.find(':'), second = line.find(':', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        const bool match = v2 ? (line.compare(0, first, "0") == 0 && controllers.empty())
                              : ("," + controllers + ",").find(",memory,") != std::string::npos;
        if (match) return line.substr(second + 1);
    }
    return std::string();
}

// The cgroup's limit minus its usage; inside a container the process's own cgroup is usually
// mounted at the root, so both its path and the root are tried.
uint64_t cgroup_left() {
    uint64_t best = kUnlimited;
    const std::string v2 = cgroup_path(true);
    for (const std::string& dir : {"/sys/fs/cgroup" + v2, std::string("/sys/fs/cgroup")}) {
        const uint64_t limit = read_number(dir + "/memory.max");
        if (limit == kUnlimited) continue;
        const uint64_t used = read_number(dir + "/memory.current");
        best = std::min(best, left(limit, used == kUnlimited ? 0 : used));
        break;
    }
    const std::string v1 = cgroup_path(false);
    for (const std::string& dir :
         {"/sys/fs/cgroup/memory" + v1, std::string("/sys/fs/cgroup/memory")}) {
        const uint64_t limit = read_number(dir + "/memory.limit_in_bytes");
        // v1 reports "no limit" as a huge page-rounded number (~2^63).
        if (limit == kUnlimited || limit >= (uint64_t(1) << 60)) continue;
        const uint64_t used = read_number(dir + "/memory.usage_in_bytes");
        best = std::min(best, left(limit, used == kUnlimited ? 0 : used));
        break;
    }
    return best;
}

// MemAvailable of /proc/meminfo in bytes; physical RAM where the kernel does not report it.
uint64_t available_memory() {
    std::ifstream in("/proc/meminfo");
    std::string key;
    unsigned long long kib = 0;
    std::string unit;
    while (in >> key >> kib) {
        std::getline(in, unit);
        if (key == "MemAvailable:") return uint64_t(kib) * 1024;
    }
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return kUnlimited;
    return uint64_t(pages) * uint64_t(page_size);
}

}  // namespace

uint64_t MemoryLimits::allowed() const {
    return std::min(address_space_left, std::min(cgroup_left, available));
}

const char* MemoryLimits::binding() const {
    const uint64_t least = allowed();
    if (least == kUnlimited) return "no limit known";
    if (least == address_space_left) return "RLIMIT_AS";
    if (least == cgroup_left) return "cgroup memory limit";
    return "available memory";
}

MemoryLimits memory_limits() {
    MemoryLimits limits;
    limits.address_space_left = address_space_left();
    limits.cgroup_left = cgroup_left();
    limits.available = available_memory();
    return limits;
}

uint64_t allocatable_memory() { return memory_limits().allowed(); }

uint64_t allocatable_memory_share(double fraction) {
    const uint64_t allowed = allocatable_memory();
    if (allowed == kUnlimited) return kUnlimited;
    return uint64_t(double(allowed) * fraction);
}

std::string format_bytes(uint64_t bytes) {
    static const char* const kUnits[] = {"bytes", "kB", "MB", "GB", "TB", "PB", "EB"};
    double value = double(bytes);
    int unit = 0;
    while (value >= 1000.0 && unit < 6) {
        value /= 1000.0;
        ++unit;
    }
    char text[32];
    if (unit == 0)
        std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
    else
        std::snprintf(text, sizeof text, "%.1f %s", value, kUnits[unit]);
    return text;
}

uint64_t saturating_mul(uint64_t a, uint64_t b) {
    if (a != 0 && b > kUnlimited / a) return kUnlimited;
    return a * b;
}

uint64_t saturating_add(uint64_t a, uint64_t b) { return b > kUnlimited - a ? kUnlimited : a + b; }

void require_memory(uint64_t bytes, const std::string& what, const std::string& fix,
                    const MemoryLimits& limits) {
    const uint64_t allowed = limits.allowed();
    if (bytes <= allowed) return;
    throw OutOfMemory(format_message(
        what, " needs ", format_bytes(bytes),
        bytes == kUnlimited ? std::string(" (more than 2^64 bytes)")
                            : format_message(" (", bytes, " bytes)"),
        "; this process may use ", format_bytes(allowed), " (", allowed,
        " bytes) more (limited by ", limits.binding(),
        "; RLIMIT_AS / cgroup / free memory): ", fix));
}

void require_memory(uint64_t bytes, const std::string& what, const std::string& fix) {
    if (bytes < (uint64_t(64) << 20)) return;  // small: not worth reading /proc
    require_memory(bytes, what, fix, memory_limits());
}

void advise_huge_pages(void* data, size_t bytes) {
#ifdef MADV_HUGEPAGE
    constexpr uintptr_t kHugePage = uintptr_t(2) << 20;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHugePage - 1);
    if (data == nullptr || end <= begin) return;
    madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // a hint: errors ignored
#else
    (void)data;
    (void)bytes;
#endif
}

}  // namespace shgi
