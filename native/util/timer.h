// Wall-clock timing for the per-stage figures solvers and renderers report (seconds, steady
// clock).
#pragma once

#include <chrono>

namespace shgi {

using TimePoint = std::chrono::steady_clock::time_point;

inline TimePoint now() { return std::chrono::steady_clock::now(); }

inline double seconds_between(TimePoint start, TimePoint end) {
    return std::chrono::duration<double>(end - start).count();
}

inline double seconds_since(TimePoint start) { return seconds_between(start, now()); }

// Adds the seconds from construction to destruction to *total (no-op when total is null, so a
// hot path pays for the clock only when someone asked for timings).
class ScopedTimer {
  public:
    explicit ScopedTimer(double* total) : total_(total), start_(total ? now() : TimePoint{}) {}
    ~ScopedTimer() {
        if (total_ != nullptr) *total_ += seconds_since(start_);
    }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

  private:
    double* total_;
    TimePoint start_;
};

}  // namespace shgi
