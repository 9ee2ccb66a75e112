// One Embree device behind RAII, with the two callbacks that keep Embree from taking the host
// process down (docs/architecture.md, "Errors"): an error callback that records the first error
// instead of printing or aborting, and a memory monitor that refuses allocations beyond a budget,
// so that a scene too large for the machine fails its commit with OutOfMemory instead of being
// killed.
//
// Included only by scene/embree_*.cpp (STYLE.md habit 7: Embree lives in one place).
// Follows the lifetime in Embree's tutorials/minimal/minimal.cpp: device, error callback first.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include <embree3/rtcore.h>

namespace shgi {

class EmbreeDevice {
  public:
    EmbreeDevice();  // throws Internal when Embree cannot create a device
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDevice get() const { return device_; }

    // Allocations that would take the device's total above `bytes` are refused.
    void set_memory_budget(uint64_t bytes) { budget_.store(bytes); }
    uint64_t memory_budget() const { return budget_.load(); }
    uint64_t bytes_in_use() const;
    // Highest bytes_in_use() since the last reset_peak().
    uint64_t peak_bytes() const;
    void reset_peak();

    // Forgets recorded errors: call before the operation whose errors throw_if_error reports.
    void clear_error();
    // Throws for the first Embree error since clear_error(): OutOfMemory (with the budget, the
    // bytes in use and the refused request), Cancelled (a progress monitor said stop) or
    // Internal; `operation` names what was being done ("building the BVH of mesh 'Cube'").
    void throw_if_error(const std::string& operation);

  private:
    static void on_error(void* self, RTCError code, const char* message);
    static bool on_memory(void* self, ssize_t bytes, bool post);

    RTCDevice device_ = nullptr;
    std::atomic<uint64_t> budget_{UINT64_MAX};
    std::atomic<int64_t> in_use_{0};
    std::atomic<int64_t> peak_{0};
    std::mutex mutex_;  // guards the recorded error below
    RTCError error_ = RTC_ERROR_NONE;
    std::string error_message_;
    uint64_t refused_bytes_ = 0;    // the allocation the memory monitor refused
    uint64_t refused_in_use_ = 0;   // bytes in use when it was refused
};

}  // namespace shgi
