// Cancel latencies that a virtual machine's host does not inflate (tests/blender/latency_clock.py
// is the same clock for the Python tests).
//
// On a virtual machine the host can run other guests on this machine's CPUs for seconds at a
// time (steal time). Those seconds pass on the wall clock while nothing of this machine runs, and
// they are no part of a cancel's latency. A LatencyClock started at the cancel measures the wall
// time since, less the steal of all CPUs over the same span: /proc/stat's first line, eighth
// value, in clock ticks. That is 0 on bare metal and where /proc/stat is missing. The bounds stay
// as tight as before, and a failure shows the wall time and the steal beside the latency.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>
#include <string>

namespace shgi::testing {

// Seconds the host has run other work on this machine's CPUs since boot (all CPUs).
inline double stolen_seconds() {
    std::ifstream stat("/proc/stat");
    std::string name;
    unsigned long long user, nice, system, idle, iowait, irq, softirq, steal;
    if (!(stat >> name >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal) ||
        name != "cpu")
        return 0.0;
    const long ticks = sysconf(_SC_CLK_TCK);
    return double(steal) / double(ticks > 0 ? ticks : 100);
}

struct Latency {
    double wall = 0.0;    // seconds on the wall clock
    double stolen = 0.0;  // seconds of them the host took from this machine's CPUs

    double seconds() const { return std::max(0.0, wall - stolen); }
    std::string describe() const {
        std::ostringstream out;
        out << seconds() << " s (" << wall << " s on the wall clock, " << stolen
            << " s of it stolen by the host)";
        return out.str();
    }
};

// Started when made (or by start()); read() is the Latency since then.
class LatencyClock {
public:
    LatencyClock() { start(); }
    void start() {
        wall_ = std::chrono::steady_clock::now();
        stolen_ = stolen_seconds();
    }
    Latency read() const {
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_).count();
        return {wall, stolen_seconds() - stolen_};
    }

private:
    std::chrono::steady_clock::time_point wall_;
    double stolen_ = 0.0;
};

}  // namespace shgi::testing
