#include "util/progress.h"

#include <algorithm>

#include "util/error.h"

namespace shgi {
namespace {

thread_local const Progress* t_calling_back = nullptr;

}  // namespace

Progress::Progress(Callback callback, double min_interval_seconds)
    : callback_(std::move(callback)),
      min_interval_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(min_interval_seconds))) {}

std::string Progress::stage() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stage_;
}

void Progress::throw_if_cancelled() const {
    if (cancelled()) throw Cancelled();
}

void Progress::begin_stage(const std::string& name, float lo, float hi) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stage_ = name;
        stage_lo_ = std::clamp(lo, 0.0f, 1.0f);
        stage_hi_ = std::clamp(hi, stage_lo_, 1.0f);
    }
    fraction_.store(stage_lo_, std::memory_order_relaxed);
    notify(true);
}

void Progress::report(uint64_t done, uint64_t total) {
    const float local = total > 0 ? static_cast<float>(static_cast<double>(done) / total) : 1.0f;
    float lo, hi;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        lo = stage_lo_;
        hi = stage_hi_;
    }
    // Parallel workers report out of order (the one that finished last may store a smaller
    // `done`), so only move forward: a completed loop must end at `hi`, not at a stale value.
    const float target = lo + std::clamp(local, 0.0f, 1.0f) * (hi - lo);
    float current = fraction_.load(std::memory_order_relaxed);
    while (target > current &&
           !fraction_.compare_exchange_weak(current, target, std::memory_order_relaxed)) {
    }
    notify(done >= total);
}

void Progress::set_fraction(float fraction) {
    fraction_.store(std::clamp(fraction, 0.0f, 1.0f), std::memory_order_relaxed);
    notify(fraction >= 1.0f);
}

const Progress* Progress::calling_back() { return t_calling_back; }

void Progress::notify(bool force) {
    if (!callback_) return;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (calling_) {  // the thread in the callback calls again for a notification it missed
            pending_ = pending_ || force;
            return;
        }
        const auto now = std::chrono::steady_clock::now();
        if (!force && now - last_notify_ < min_interval_) return;
        last_notify_ = now;
        calling_ = true;
    }
    const Progress* outer = t_calling_back;
    t_calling_back = this;
    for (;;) {
        call_back();
        std::lock_guard<std::mutex> lock(mutex_);
        if (!pending_) {
            calling_ = false;
            break;
        }
        pending_ = false;
        last_notify_ = std::chrono::steady_clock::now();
    }
    t_calling_back = outer;
}

std::exception_ptr Progress::callback_failure() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return callback_failure_;
}

void Progress::call_back() {
    // A failing callback (e.g. a Python exception) cancels the work instead of unwinding
    // through a worker thread; the first failure is kept for the caller to report.
    std::exception_ptr failure;
    try {
        callback_(fraction(), stage());
        return;
    } catch (...) {
        failure = std::current_exception();
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!callback_failure_) callback_failure_ = failure;
    }
    cancel();
}

}  // namespace shgi
