// Progress of a long operation: fraction done, stage name, cancel flag, optional callback.
//
// docs/architecture.md, "Progress and cancel": every long call takes a Progress and polls it
// between chunks of work; once cancel() is called the work stops within a chunk and the call throws
// Cancelled (< 0.2 s for the chunk sizes SHGI uses). All members are thread-safe: workers report,
// the caller (or a UI thread) reads and cancels.
//
// Multi-stage work maps each stage onto a sub-range of [0, 1] with begin_stage(name, lo, hi);
// report(done, total) inside the stage then moves the overall fraction from lo to hi.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <string>

namespace shgi {

class Progress {
  public:
    // Called with (overall fraction in [0,1], stage name). It may run on any thread, but never
    // on two at once, and at most every `min_interval` (plus once at each stage start and at 1).
    // No lock is held while it runs: it may read this Progress, cancel it, or start other work
    // with it. A notification due while the callback runs (from another thread, or from work
    // the callback started) is not waited for: the running call is followed by one more call
    // with the latest state instead.
    using Callback = std::function<void(float fraction, const std::string& stage)>;

    Progress() = default;
    explicit Progress(Callback callback, double min_interval_seconds = 0.05);
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    // --- caller side ---
    void cancel() { cancelled_.store(true, std::memory_order_relaxed); }
    bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }
    float fraction() const { return fraction_.load(std::memory_order_relaxed); }
    std::string stage() const;

    // --- worker side ---
    // Throws Cancelled if cancel() was called.
    void throw_if_cancelled() const;
    void begin_stage(const std::string& name, float lo = 0.0f, float hi = 1.0f);
    // `done` of `total` units of the current stage are finished.
    void report(uint64_t done, uint64_t total);
    // Sets the overall fraction directly.
    void set_fraction(float fraction);

    // What the callback threw first, or null. A throwing callback cancels the work, which then
    // ends in Cancelled; the caller may raise this in its place (the bindings do).
    std::exception_ptr callback_failure() const;

    // The Progress whose callback this thread is running, or nullptr: work that would wait for
    // the operation reporting to that Progress must refuse instead (it would wait for itself).
    static const Progress* calling_back();

  private:
    void notify(bool force);
    void call_back();  // runs callback_ once; a failure in it cancels

    std::atomic<bool> cancelled_{false};
    std::atomic<float> fraction_{0.0f};
    float stage_lo_ = 0.0f, stage_hi_ = 1.0f;
    mutable std::mutex mutex_;  // guards stage_ and the callback bookkeeping, never held in it
    std::string stage_;
    bool calling_ = false;  // a thread is running the callback
    bool pending_ = false;  // a forced notification came while it ran: call once more
    Callback callback_;
    std::exception_ptr callback_failure_;  // guarded by mutex_
    std::chrono::steady_clock::duration min_interval_{};
    std::chrono::steady_clock::time_point last_notify_{};
};

// Polls an optional Progress: the idiom for code that takes `Progress* progress = nullptr`.
inline void throw_if_cancelled(const Progress* progress) {
    if (progress) progress->throw_if_cancelled();
}

// A long sequential pass over [0, count) as body(begin, end) calls on slices of at most `slice`
// items, with a cancel poll before each: the poll stays out of the per-item loop.
template <typename Body>
void for_each_slice(uint64_t count, uint64_t slice, const Progress* progress, Body&& body) {
    for (uint64_t begin = 0; begin < count; begin += slice) {
        throw_if_cancelled(progress);
        body(begin, count - begin < slice ? count : begin + slice);
    }
}

}  // namespace shgi
