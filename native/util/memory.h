// The memory this process may still use, and the check every large allocation makes first
// (docs/robustness-memory.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace shgi {

// What bounds the memory this process may still allocate, each in bytes; UINT64_MAX where the
// system sets no such bound or does not say.
struct MemoryLimits {
    uint64_t address_space_left = UINT64_MAX;  // RLIMIT_AS minus the current virtual size
    uint64_t cgroup_left = UINT64_MAX;         // the cgroup's memory limit minus its usage
    uint64_t available = UINT64_MAX;           // MemAvailable of /proc/meminfo
    // The smallest of the three: what the process may still allocate.
    uint64_t allowed() const;
    // Which bound gives allowed(): "RLIMIT_AS", "cgroup memory limit", "available memory" or
    // "no limit known".
    const char* binding() const;
};

// Reads the limits now: getrlimit(RLIMIT_AS) and /proc/self/statm, the cgroup v2
// (memory.max, memory.current) or v1 (memory.limit_in_bytes, memory.usage_in_bytes) files of
// the process's cgroup, and /proc/meminfo.
MemoryLimits memory_limits();

// Bytes this process may still allocate: memory_limits().allowed().
uint64_t allocatable_memory();

// `fraction` of allocatable_memory(): for budgets that default to a share of what is left.
uint64_t allocatable_memory_share(double fraction);

// Throws OutOfMemory when `bytes` is more than allocatable_memory():
//   "<what> needs 34.4 GB (34359738368 bytes); this process may use 20.1 GB (...) more
//    (limited by RLIMIT_AS): <fix>"
// `what` names the setting and its value ("TexelRasterSettings.width x height = 16384 x 16384
// with 4 samples per texel"), `fix` says what to change ("lower the resolution").
void require_memory(uint64_t bytes, const std::string& what, const std::string& fix);

// The same against an explicit allowance (tests, and callers with their own budget).
void require_memory(uint64_t bytes, const std::string& what, const std::string& fix,
                    const MemoryLimits& limits);

// "34.4 GB" (decimal units, 3 significant digits) for messages.
std::string format_bytes(uint64_t bytes);

// a * b, or UINT64_MAX when the product overflows: estimates never wrap around to small sizes.
uint64_t saturating_mul(uint64_t a, uint64_t b);
uint64_t saturating_add(uint64_t a, uint64_t b);

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with huge pages
// (transparent huge pages in "madvise" mode): a buffer of hundreds of MB then takes ~500 times
// fewer page faults to fill and is freed that much faster. A hint; ignored where unsupported.
void advise_huge_pages(void* data, size_t bytes);

}  // namespace shgi
