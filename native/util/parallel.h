// Parallel loops on TBB that poll a cancel flag and report progress.
//
// parallel_for splits [begin, end) by halving until chunks hold at most `grain` items (TBB's
// simple_partitioner: chunks of grain/2 to grain items whose boundaries depend only on the range
// and the grain, never on the thread count) and calls body(chunk_begin, chunk_end).
// Bodies must write only to their own items; with per-item RNG streams (util/rng.h) the result
// is then bit-identical for any thread count. Before each chunk the Progress is polled; after a
// cancel no new chunk starts and parallel_for throws Cancelled once the running chunks finish.
// An exception thrown by a body cancels the other chunks and is rethrown to the caller.
#pragma once

#include <atomic>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_group.h>

#include "util/error.h"
#include "util/progress.h"

namespace shgi {

template <typename Body>
void parallel_for(uint64_t begin, uint64_t end, uint64_t grain, Body&& body,
                  Progress* progress = nullptr) {
    if (end <= begin) return;
    grain = grain == 0 ? 1 : grain;
    const uint64_t total = end - begin;
    std::atomic<uint64_t> done{0};
    std::atomic<bool> stopped{false};
    tbb::task_group_context context;
    tbb::parallel_for(
        tbb::blocked_range<uint64_t>(begin, end, grain),
        [&](const tbb::blocked_range<uint64_t>& range) {
            if (stopped.load(std::memory_order_relaxed)) return;
            if (progress && progress->cancelled()) {
                stopped.store(true, std::memory_order_relaxed);
                context.cancel_group_execution();
                return;
            }
            body(range.begin(), range.end());
            const uint64_t now_done = done.fetch_add(range.size()) + range.size();
            if (progress) progress->report(now_done, total);
        },
        tbb::simple_partitioner(), context);
    if (stopped.load() || (progress && progress->cancelled() && done.load() < total))
        throw Cancelled();
}

// Maximum worker threads SHGI uses (TBB's default: all cores). Scoped override for tests that
// check thread-count independence.
int max_threads();

}  // namespace shgi
