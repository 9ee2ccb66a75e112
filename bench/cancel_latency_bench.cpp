// Cancel latency of long photon work on the Cornell box: how long a call takes to throw Cancelled
// (and free what it made) after Progress::cancel().
// - trace_photons, a pass of 2 x 10^8 photons cancelled after each of `seconds`: later cancels
//   find larger maps, so they also measure the slice-wise growth of the maps and freeing them.
// - PhotonLattice::solve of 10^7 photons, cancelled at 70-99% of the time a full solve takes,
//   the later ones in the injection of ~2 x 10^7 stored photons.
// - the PhotonMap (k-d tree shards) over 10^7 photons that caustics = PhotonMap rebuilds after
//   every pass once a map has grown that large, cancelled at 10-90% of its full build time.
// A plain main printing figures: benchmarks are not tests.
//
//   build/bench/cancel_latency_bench [seconds ...]   (default: 0.25 0.5 1 2 4 8)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "bench_scenes.h"
#include "lattice/photon_lattice.h"
#include "photon/photon_map.h"
#include "photon/photon_tracer.h"
#include "util/error.h"
#include "util/progress.h"
#include "util/rng.h"
#include "util/timer.h"

using namespace shgi;

namespace {

// Runs work(progress) with a cancel after `after` seconds; prints the latency and the stage the
// cancel found.
template <typename Work>
void cancel_after_seconds(double after, Work&& work) {
    Progress progress;
    TimePoint cancelled_at;
    std::string stage;
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::duration<double>(after));
        cancelled_at = now();
        stage = progress.stage();
        progress.cancel();
    });
    bool cancelled = false;
    try {
        work(&progress);
    } catch (const Cancelled&) {
        cancelled = true;
    } catch (...) {
        canceller.join();  // a joinable thread's destructor would terminate instead
        throw;
    }
    const TimePoint returned = now();
    canceller.join();
    if (!cancelled) {
        std::printf("  %5.2f s: finished before the cancel\n", after);
        return;
    }
    std::printf("  %5.2f s: Cancelled %.1f ms after cancel()%s%s\n", after,
                1e3 * seconds_between(cancelled_at, returned), stage.empty() ? "" : ", in stage ",
                stage.c_str());
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<double> times;
    for (int i = 1; i < argc; ++i) times.push_back(std::atof(argv[i]));
    if (times.empty()) times = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
    Scene scene = bench::cornell_box(64, 36);
    scene.commit();
    PhotonTracerSettings settings;
    settings.photons = 200000000;
    std::printf("cornell box, %llu photons per pass, cancelled after:\n",
                static_cast<unsigned long long>(settings.photons));
    for (const double after : times)
        cancel_after_seconds(after, [&](Progress* progress) {
            trace_photons(scene, settings, 0, progress);
        });

    PhotonLatticeSettings solve_settings;
    solve_settings.photons = 10000000;
    PhotonLattice lattice(scene, solve_settings);
    lattice.solve();  // the first solve also touches its memory for the first time: slower
    const TimePoint start = now();
    lattice.solve();
    const double full = seconds_since(start);
    std::printf("PhotonLattice::solve of %llu photons: %.2f s in full (trace %.2f, injection "
                "%.2f); cancelled after:\n",
                static_cast<unsigned long long>(solve_settings.photons), full,
                lattice.timings().emit_trace, lattice.timings().injection);
    for (const double fraction : {0.7, 0.88, 0.92, 0.96, 0.99})
        cancel_after_seconds(fraction * full, [&](Progress* progress) { lattice.solve(progress); });

    // Photons spread through the room's volume (a caustic map's photons lie on surfaces, which
    // only changes the tree's shape, not the work of building it).
    std::vector<Photon> photons(10000000);
    Pcg32 rng(3, 0);
    for (Photon& photon : photons) {
        photon.position = vec3(rng.next_float(), rng.next_float(), rng.next_float());
        photon.power = vec3(1.0f);
        photon.normal = photon.direction = vec3(0.0f, 0.0f, 1.0f);
    }
    // Each build gets its own copy, made before the clock starts.
    std::vector<Photon> copy = photons;
    const TimePoint build_start = now();
    const PhotonMap built(std::move(copy));
    const double build = seconds_since(build_start);
    std::printf("PhotonMap of %zu photons: built in %.2f s (%zu shards); cancelled after:\n",
                photons.size(), build, built.shard_count());
    for (const double fraction : {0.1, 0.3, 0.5, 0.7, 0.9}) {
        copy = photons;
        cancel_after_seconds(fraction * build, [&](Progress* progress) {
            const PhotonMap map(std::move(copy), 1.0f, progress);
        });
    }
    return 0;
}
