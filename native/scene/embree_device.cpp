#include "scene/embree_device.h"

#include "util/error.h"

namespace shgi {
namespace {

const char* error_name(RTCError code) {
    switch (code) {
        case RTC_ERROR_NONE: return "no error";
        case RTC_ERROR_UNKNOWN: return "unknown error";
        case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
        case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
        case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
        case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
        case RTC_ERROR_CANCELLED: return "cancelled";
    }
    return "unrecognised error";
}

}  // namespace

EmbreeDevice::EmbreeDevice() {
    device_ = rtcNewDevice(nullptr);
    if (!device_)
        throw Internal(format_message("Embree could not create a device: ",
                                      error_name(rtcGetDeviceError(nullptr))));
    rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, this);
    rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeDevice::on_memory, this);
}

EmbreeDevice::~EmbreeDevice() {
    // Scenes and geometries hold references to the device; their owners release them first.
    rtcReleaseDevice(device_);
}

uint64_t EmbreeDevice::bytes_in_use() const {
    const int64_t bytes = in_use_.load();
    return bytes > 0 ? static_cast<uint64_t>(bytes) : 0;
}

uint64_t EmbreeDevice::peak_bytes() const {
    const int64_t bytes = peak_.load();
    return bytes > 0 ? static_cast<uint64_t>(bytes) : 0;
}

void EmbreeDevice::reset_peak() { peak_.store(in_use_.load()); }

void EmbreeDevice::clear_error() {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = RTC_ERROR_NONE;
    error_message_.clear();
    refused_bytes_ = refused_in_use_ = 0;
    rtcGetDeviceError(device_);  // also resets Embree's own sticky error code
}

void EmbreeDevice::throw_if_error(const std::string& operation) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_ == RTC_ERROR_NONE) return;
    const RTCError code = error_;
    error_ = RTC_ERROR_NONE;
    if (code == RTC_ERROR_CANCELLED) throw Cancelled();
    if (code == RTC_ERROR_OUT_OF_MEMORY && refused_bytes_ > 0)
        throw OutOfMemory(format_message(
            operation, " exceeded the memory budget: budget ", budget_.load(), " bytes, ",
            refused_in_use_, " bytes in use, ", refused_bytes_,
            " more bytes requested; raise memory_budget_bytes (0 = 75% of what the process may "
            "still allocate: RLIMIT_AS / cgroup / free memory) or "
            "simplify the scene"));
    if (code == RTC_ERROR_OUT_OF_MEMORY)
        throw OutOfMemory(format_message(operation, ": Embree ran out of memory (",
                                         error_message_, ")"));
    throw Internal(format_message(operation, ": Embree reported ", error_name(code), " (",
                                  error_message_, ")"));
}

void EmbreeDevice::on_error(void* self, RTCError code, const char* message) {
    auto* device = static_cast<EmbreeDevice*>(self);
    std::lock_guard<std::mutex> lock(device->mutex_);
    if (device->error_ != RTC_ERROR_NONE) return;  // the first error is the cause
    device->error_ = code;
    device->error_message_ = message ? message : "";
}

bool EmbreeDevice::on_memory(void* self, ssize_t bytes, bool /*post*/) {
    auto* device = static_cast<EmbreeDevice*>(self);
    const int64_t now = device->in_use_.fetch_add(bytes) + bytes;
    if (bytes > 0 && static_cast<uint64_t>(now) > device->budget_.load()) {
        // A refused allocation is never made, so Embree never reports freeing it: undo it.
        device->in_use_.fetch_sub(bytes);
        std::lock_guard<std::mutex> lock(device->mutex_);
        if (device->refused_bytes_ == 0) {
            device->refused_bytes_ = static_cast<uint64_t>(bytes);
            device->refused_in_use_ = static_cast<uint64_t>(now - bytes);
        }
        return false;
    }
    int64_t peak = device->peak_.load();
    while (now > peak && !device->peak_.compare_exchange_weak(peak, now)) {
    }
    return true;
}

}  // namespace shgi
