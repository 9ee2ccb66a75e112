// memory_limits / allocatable_memory / require_memory: the allowance every large allocation
// checks first (docs/robustness-memory.md), with RLIMIT_AS set in a forked child.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "support/expect_error.h"
#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

using testing::expect_contains;

TEST(Memory, AllowedIsTheSmallestLimit) {
    MemoryLimits limits;
    limits.address_space_left = 5000;
    limits.cgroup_left = 3000;
    limits.available = 4000;
    EXPECT_EQ(limits.allowed(), 3000u);
    EXPECT_STREQ(limits.binding(), "cgroup memory limit");
    limits.address_space_left = 1000;
    EXPECT_EQ(limits.allowed(), 1000u);
    EXPECT_STREQ(limits.binding(), "RLIMIT_AS");
    EXPECT_STREQ(MemoryLimits{}.binding(), "no limit known");
}

TEST(Memory, TheMachineReportsAvailableMemory) {
    const MemoryLimits limits = memory_limits();
    EXPECT_GT(limits.available, 0u);
    EXPECT_LT(limits.available, UINT64_MAX);
    EXPECT_LE(allocatable_memory(), limits.available);
}

TEST(Memory, RequireMemoryNamesTheSettingTheBytesAndTheFix) {
    MemoryLimits limits;
    limits.available = 20'100'000'000;
    EXPECT_NO_THROW(require_memory(20'100'000'000, "x", "y", limits));
    const std::string message = testing::rejection<OutOfMemory>([&] {
        require_memory(34'400'000'000, "TexelRasterSettings.width x height = 16384 x 16384",
                       "lower the resolution", limits);
    });
    EXPECT_EQ(message,
              "TexelRasterSettings.width x height = 16384 x 16384 needs 34.4 GB (34400000000 "
              "bytes); this process may use 20.1 GB (20100000000 bytes) more (limited by "
              "available memory; RLIMIT_AS / cgroup / free memory): lower the resolution");
    expect_contains(testing::rejection<OutOfMemory>([&] {
                        require_memory(UINT64_MAX, "photons", "fewer", limits);
                    }),
                    "needs 18.4 EB (more than 2^64 bytes)");
}

TEST(Memory, SaturatingArithmeticNeverWraps) {
    EXPECT_EQ(saturating_mul(uint64_t(1) << 40, uint64_t(1) << 30), UINT64_MAX);
    EXPECT_EQ(saturating_mul(3, 4), 12u);
    EXPECT_EQ(saturating_add(UINT64_MAX - 1, 5), UINT64_MAX);
    EXPECT_EQ(format_bytes(999), "999 bytes");
    EXPECT_EQ(format_bytes(1'500'000), "1.5 MB");
}

// The virtual size of this process in bytes, from /proc/self/statm.
uint64_t virtual_size() {
    std::ifstream in("/proc/self/statm");
    uint64_t pages = 0;
    in >> pages;
    return pages * uint64_t(sysconf(_SC_PAGE_SIZE));
}

TEST(Memory, RlimitAsBoundsTheAllowanceInAChild) {
    // A child process, so that the limit does not reach the other tests.
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        const uint64_t limit = virtual_size() + (uint64_t(256) << 20);
        const rlimit as{limit, limit};
        if (setrlimit(RLIMIT_AS, &as) != 0) _exit(10);
        const MemoryLimits limits = memory_limits();
        const uint64_t expected = limit - virtual_size();
        // Left = limit - virtual size, read a moment apart (within 16 MiB).
        if (limits.address_space_left > expected + (uint64_t(16) << 20)) _exit(11);
        if (limits.address_space_left + (uint64_t(16) << 20) < expected) _exit(12);
        if (limits.allowed() != limits.address_space_left) _exit(13);
        if (std::string(limits.binding()) != "RLIMIT_AS") _exit(14);
        try {
            require_memory(uint64_t(1) << 30, "a gigabyte", "less");
            _exit(15);
        } catch (const OutOfMemory& error) {
            if (std::string(error.what()).find("limited by RLIMIT_AS") == std::string::npos)
                _exit(16);
        }
        _exit(0);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "exit code names the failed check (10..16)";
}

}  // namespace
}  // namespace shgi
