// Cancel latency of a long photon pass: how long trace_photons takes to throw Cancelled (and free
// what it stored) after Progress::cancel(), for cancels at several times into a pass of 2 x 10^8
// photons on the Cornell box. Later cancels find larger maps, so they also measure the slice-wise
// growth of the maps and the cost of freeing them. A plain main printing figures: benchmarks are
// not tests.
//
//   build/bench/cancel_latency_bench [seconds ...]   (default: 0.25 0.5 1 2 4 8)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "bench_scenes.h"
#include "photon/photon_tracer.h"
#include "util/error.h"
#include "util/progress.h"

using namespace shgi;

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

int main(int argc, char** argv) {
    std::vector<double> cancel_after;
    for (int i = 1; i < argc; ++i) cancel_after.push_back(std::atof(argv[i]));
    if (cancel_after.empty()) cancel_after = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
    Scene scene = bench::cornell_box(64, 36);
    scene.commit();
    PhotonTracerSettings settings;
    settings.photons = 200000000;
    std::printf("cornell box, %llu photons per pass, cancelled after:\n",
                static_cast<unsigned long long>(settings.photons));
    for (const double after : cancel_after) {
        Progress progress;
        Clock::time_point cancelled_at;
        std::thread canceller([&] {
            std::this_thread::sleep_for(std::chrono::duration<double>(after));
            cancelled_at = Clock::now();
            progress.cancel();
        });
        bool cancelled = false;
        try {
            trace_photons(scene, settings, 0, &progress);
        } catch (const Cancelled&) {
            cancelled = true;
        }
        const Clock::time_point returned = Clock::now();
        canceller.join();
        if (!cancelled) {
            std::printf("  %5.2f s: the pass finished before the cancel\n", after);
            continue;
        }
        std::printf("  %5.2f s: Cancelled %.1f ms after cancel()\n", after,
                    1e3 * seconds(returned - cancelled_at));
    }
    return 0;
}
