// parallel_for: thread-count independence, cancellation, exception propagation, progress.
#include "util/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include <tbb/global_control.h>

#include "util/rng.h"

namespace shgi {
namespace {

constexpr uint64_t kItems = 10000;
constexpr uint64_t kGrain = 64;

// Each item draws from its own stream (docs/architecture.md, "Determinism") and does a little work.
std::vector<float> per_item_work(int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    EXPECT_EQ(max_threads(), threads);
    std::vector<float> out(kItems, 0.0f);
    parallel_for(0, kItems, kGrain, [&](uint64_t begin, uint64_t end) {
        for (uint64_t i = begin; i < end; ++i) {
            Pcg32 rng(77, stream_id(3, i));
            float sum = 0.0f;
            for (int k = 0; k < 50; ++k) sum += rng.next_float() * static_cast<float>(k);
            out[i] = sum;
        }
    });
    return out;
}

TEST(ParallelFor, ResultsAreIdenticalForAnyThreadCount) {
    const std::vector<float> one = per_item_work(1);
    const std::vector<float> two = per_item_work(2);
    ASSERT_EQ(one.size(), two.size());
    for (size_t i = 0; i < one.size(); ++i) ASSERT_EQ(one[i], two[i]) << "item " << i;
}

TEST(ParallelFor, VisitsEveryItemOnceAndReportsCompletion) {
    std::vector<std::atomic<int>> visits(kItems);
    Progress progress;
    parallel_for(
        0, kItems, kGrain,
        [&](uint64_t begin, uint64_t end) {
            ASSERT_LE(end - begin, kGrain);  // simple_partitioner: chunks never exceed the grain
            for (uint64_t i = begin; i < end; ++i) visits[i].fetch_add(1);
        },
        &progress);
    for (uint64_t i = 0; i < kItems; ++i) ASSERT_EQ(visits[i].load(), 1) << "item " << i;
    EXPECT_FLOAT_EQ(progress.fraction(), 1.0f);
    int calls = 0;
    parallel_for(5, 5, 1, [&](uint64_t, uint64_t) { ++calls; });
    EXPECT_EQ(calls, 0);
}

// A cancel from inside the work (as from a UI thread mid-run) stops new chunks: at most the
// chunks already running on other threads start after it, and the call throws Cancelled.
// (TBB's simple_partitioner halves the range until a chunk is <= grain, so chunk boundaries are
// not multiples of the grain; the cancel fires in the chunk that holds item kCancelItem.)
TEST(ParallelFor, CancelThrowsCancelledPromptly) {
    constexpr uint64_t kCancelItem = 640;
    std::atomic<uint64_t> total_chunks{0};
    parallel_for(0, kItems, kGrain, [&](uint64_t, uint64_t) { total_chunks.fetch_add(1); });
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        Progress progress;
        std::atomic<uint64_t> chunks_run{0}, chunks_after_cancel{0};
        const auto body = [&](uint64_t begin, uint64_t end) {
            if (progress.cancelled()) chunks_after_cancel.fetch_add(1);
            chunks_run.fetch_add(1);
            if (begin <= kCancelItem && kCancelItem < end) progress.cancel();
        };
        EXPECT_THROW(parallel_for(0, kItems, kGrain, body, &progress), Cancelled);
        EXPECT_LE(chunks_after_cancel.load(), static_cast<uint64_t>(threads));
        EXPECT_LT(chunks_run.load(), total_chunks.load()) << "work continued after cancel";
    }
}

TEST(ParallelFor, AlreadyCancelledRunsNothing) {
    Progress progress;
    progress.cancel();
    std::atomic<int> calls{0};
    EXPECT_THROW(parallel_for(0, kItems, kGrain, [&](uint64_t, uint64_t) { ++calls; }, &progress),
                 Cancelled);
    EXPECT_EQ(calls.load(), 0);
}

TEST(ParallelFor, ExceptionInBodyPropagatesWithItsType) {
    const auto failing = [](uint64_t begin, uint64_t end) {
        if (begin <= 777 && 777 < end) throw InvalidArgument("item 777 is bad");
    };
    try {
        parallel_for(0, kItems, kGrain, failing);
        FAIL() << "no exception";
    } catch (const InvalidArgument& error) {
        EXPECT_STREQ(error.what(), "item 777 is bad");
    }
    EXPECT_THROW(parallel_for(0, kItems, 1,
                              [](uint64_t begin, uint64_t) {
                                  if (begin == 3) throw std::runtime_error("boom");
                              }),
                 std::runtime_error);
}

}  // namespace
}  // namespace shgi
