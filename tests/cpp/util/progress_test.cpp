// Progress: stage mapping onto [0, 1], callback throttling, cancel, failing callbacks.
#include "util/progress.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "util/error.h"
#include "util/log.h"
#include "util/parallel.h"

namespace shgi {
namespace {

constexpr float kExact = 1e-6f;
// Long enough that no two un-forced notifications of a test can fall in different intervals.
constexpr double kLongInterval = 3600.0;

TEST(Progress, StagesMapOntoSubranges) {
    Progress progress;
    progress.begin_stage("trace", 0.2f, 0.6f);
    EXPECT_EQ(progress.stage(), "trace");
    EXPECT_NEAR(progress.fraction(), 0.2f, kExact);
    progress.report(1, 4);
    EXPECT_NEAR(progress.fraction(), 0.3f, kExact);
    progress.report(4, 4);
    EXPECT_NEAR(progress.fraction(), 0.6f, kExact);
    progress.report(9, 4);  // over-reporting clamps to the stage end
    EXPECT_NEAR(progress.fraction(), 0.6f, kExact);
    progress.begin_stage("gather", 0.6f, 1.0f);
    progress.report(1, 2);
    EXPECT_NEAR(progress.fraction(), 0.8f, kExact);
    progress.report(0, 0);  // an empty stage is complete
    EXPECT_NEAR(progress.fraction(), 1.0f, kExact);
}

TEST(Progress, ForEachSliceCoversTheRangeAndPollsBeforeEachSlice) {
    std::vector<std::pair<uint64_t, uint64_t>> slices;
    const auto record = [&](uint64_t begin, uint64_t end) { slices.emplace_back(begin, end); };
    for_each_slice(10, 4, nullptr, record);
    EXPECT_EQ(slices, (std::vector<std::pair<uint64_t, uint64_t>>{{0, 4}, {4, 8}, {8, 10}}));
    slices.clear();
    for_each_slice(0, 4, nullptr, record);
    EXPECT_TRUE(slices.empty());
    // Cancelled by the second slice: the third is never started.
    Progress progress;
    slices.clear();
    EXPECT_THROW(for_each_slice(10, 4, &progress,
                                [&](uint64_t begin, uint64_t end) {
                                    record(begin, end);
                                    if (slices.size() == 2) progress.cancel();
                                }),
                 Cancelled);
    EXPECT_EQ(slices.size(), 2u);
}

TEST(Progress, StageBoundsAreClamped) {
    Progress progress;
    progress.begin_stage("odd", 0.7f, 0.3f);  // hi < lo collapses to lo
    progress.report(1, 2);
    EXPECT_NEAR(progress.fraction(), 0.7f, kExact);
    progress.begin_stage("wide", -1.0f, 2.0f);
    progress.report(1, 2);
    EXPECT_NEAR(progress.fraction(), 0.5f, kExact);
    progress.set_fraction(3.0f);
    EXPECT_NEAR(progress.fraction(), 1.0f, kExact);
}

TEST(Progress, CallbackIsThrottledButStageStartsAndCompletionAreForced) {
    std::vector<std::pair<float, std::string>> calls;
    Progress progress([&](float f, const std::string& s) { calls.emplace_back(f, s); },
                      kLongInterval);
    progress.begin_stage("a", 0.0f, 0.5f);  // forced
    for (int i = 1; i < 100; ++i) progress.report(i, 100);  // throttled
    progress.report(100, 100);             // forced: stage complete
    progress.begin_stage("b", 0.5f, 1.0f);  // forced
    progress.report(50, 100);              // throttled
    progress.set_fraction(1.0f);           // forced
    ASSERT_EQ(calls.size(), 4u);
    EXPECT_EQ(calls[0].second, "a");
    EXPECT_NEAR(calls[0].first, 0.0f, kExact);
    EXPECT_NEAR(calls[1].first, 0.5f, kExact);
    EXPECT_EQ(calls[2].second, "b");
    EXPECT_NEAR(calls[3].first, 1.0f, kExact);
}

TEST(Progress, ZeroIntervalCallsBackEveryTime) {
    int calls = 0;
    Progress progress([&](float, const std::string&) { ++calls; }, 0.0);
    for (int i = 1; i <= 10; ++i) progress.report(i, 10);
    EXPECT_EQ(calls, 10);
}

TEST(Progress, CancelIsSeenByWorkers) {
    Progress progress;
    EXPECT_FALSE(progress.cancelled());
    EXPECT_NO_THROW(progress.throw_if_cancelled());
    progress.cancel();
    EXPECT_TRUE(progress.cancelled());
    EXPECT_THROW(progress.throw_if_cancelled(), Cancelled);
    EXPECT_THROW(throw_if_cancelled(&progress), Cancelled);
    EXPECT_NO_THROW(throw_if_cancelled(nullptr));
}

TEST(Progress, FailingCallbackCancelsInsteadOfUnwindingAndKeepsItsFirstFailure) {
    int calls = 0;
    Progress progress([&calls](float, const std::string&) {
        throw std::runtime_error(++calls == 1 ? "ui gone" : "second failure");
    });
    EXPECT_EQ(progress.callback_failure(), nullptr);
    EXPECT_NO_THROW(progress.begin_stage("work"));
    EXPECT_TRUE(progress.cancelled());
    EXPECT_NO_THROW(progress.begin_stage("more work"));
    EXPECT_EQ(calls, 2);
    ASSERT_NE(progress.callback_failure(), nullptr);
    try {
        std::rethrow_exception(progress.callback_failure());
    } catch (const std::runtime_error& error) {
        EXPECT_STREQ(error.what(), "ui gone");
    }
}

// "never on two threads at once": reports from parallel workers are serialised.
TEST(Progress, CallbackNeverRunsConcurrently) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    std::atomic<int> inside{0}, max_inside{0}, calls{0};
    Progress progress(
        [&](float, const std::string&) {
            const int now = inside.fetch_add(1) + 1;
            int seen = max_inside.load();
            while (now > seen && !max_inside.compare_exchange_weak(seen, now)) {
            }
            calls.fetch_add(1);
            inside.fetch_sub(1);
        },
        0.0);
    parallel_for(0, 20000, 10, [](uint64_t, uint64_t) {}, &progress);
    EXPECT_EQ(max_inside.load(), 1);
    EXPECT_GT(calls.load(), 0);
    EXPECT_NEAR(progress.fraction(), 1.0f, kExact);
}

// No lock is held in the callback: it reads its Progress and reports to it (work it started)
// without waiting for itself; a forced notification it caused is delivered by one more call.
TEST(Progress, CallbackMayUseItsProgressAndMissedStagesAreDeliveredAfterIt) {
    std::vector<std::string> stages;
    Progress* self = nullptr;
    Progress progress(
        [&](float, const std::string& stage) {
            EXPECT_EQ(Progress::calling_back(), self);
            EXPECT_EQ(self->stage(), stage);
            stages.push_back(stage);
            if (stages.size() == 1) self->begin_stage("nested");  // re-enters notify()
        },
        10.0);
    self = &progress;
    EXPECT_EQ(Progress::calling_back(), nullptr);
    progress.begin_stage("outer");
    EXPECT_EQ(Progress::calling_back(), nullptr);
    EXPECT_EQ(stages, (std::vector<std::string>{"outer", "nested"}));
}

}  // namespace
}  // namespace shgi
