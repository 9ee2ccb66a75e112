// sort_by_cell / for_each_cell / sum_by_cell: equal to a serial reference counting sort,
// bit-identical for 1 and 2 threads, empty input and empty cells, bad cell indices refused.
#include "util/cell_sort.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "support/expect_error.h"
#include "util/rng.h"

namespace shgi {
namespace {

// The obvious serial stable grouping: for every cell, scan all items in order.
ItemsByCell reference_sort(const std::vector<uint32_t>& item_cell, size_t cells) {
    ItemsByCell sorted;
    sorted.start.push_back(0);
    for (size_t c = 0; c < cells; ++c) {
        for (size_t i = 0; i < item_cell.size(); ++i)
            if (item_cell[i] == c) sorted.order.push_back(uint32_t(i));
        sorted.start.push_back(uint32_t(sorted.order.size()));
    }
    return sorted;
}

// `items` random cells in [0, cells), every 7th item in no cell, and cell 3 always empty (so
// both empty cells and skipped items occur). Enough items for several sort blocks.
std::vector<uint32_t> random_cells(uint64_t items, uint32_t cells, uint64_t seed) {
    std::vector<uint32_t> item_cell(items);
    for (uint64_t i = 0; i < items; ++i) {
        Pcg32 rng(seed, stream_id(0, i));
        uint32_t cell = uint32_t(rng.next_float() * float(cells)) % cells;
        if (cell == 3) cell = 4;
        item_cell[i] = i % 7 == 0 ? kNoCell : cell;
    }
    return item_cell;
}

struct Sorted {
    ItemsByCell sorted;
    std::vector<float> sums;
};

// A float sum per cell whose value depends on the summation order (mixed magnitudes).
float item_power(uint32_t i) { return i % 3 == 0 ? 1e4f + 0.1f * float(i) : 1e-3f * float(i); }

Sorted sort_with_threads(const std::vector<uint32_t>& item_cell, size_t cells, int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    EXPECT_EQ(max_threads(), threads);
    Sorted out;
    out.sorted = sort_by_cell(item_cell, cells);
    out.sums = sum_by_cell(out.sorted, 0.0f, item_power);
    return out;
}

constexpr uint32_t kCells = 50;
// Several blocks of kCellSortItemsPerBlock, the last one partial.
constexpr uint64_t kItems = 3 * kCellSortItemsPerBlock + 1234;

TEST(CellSort, EqualsSerialReference) {
    const std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 11);
    const ItemsByCell sorted = sort_by_cell(item_cell, kCells);
    const ItemsByCell reference = reference_sort(item_cell, kCells);
    EXPECT_EQ(sorted.start, reference.start);
    EXPECT_EQ(sorted.order, reference.order);
    EXPECT_EQ(sorted.cell_count(), size_t(kCells));
    EXPECT_EQ(sorted.count(3), 0u);  // the empty cell
    EXPECT_EQ(sorted.order.size(), kItems - (kItems + 6) / 7);  // every 7th item skipped
}

TEST(CellSort, IdenticalForOneAndTwoThreads) {
    const std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 12);
    const Sorted one = sort_with_threads(item_cell, kCells, 1);
    const Sorted two = sort_with_threads(item_cell, kCells, 2);
    EXPECT_EQ(one.sorted.start, two.sorted.start);
    EXPECT_EQ(one.sorted.order, two.sorted.order);
    ASSERT_EQ(one.sums.size(), two.sums.size());
    for (size_t c = 0; c < one.sums.size(); ++c)
        EXPECT_EQ(one.sums[c], two.sums[c]) << "cell " << c;  // bitwise: same order of adds
}

TEST(CellSort, SumByCellAddsInInputOrder) {
    const std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 13);
    const ItemsByCell sorted = sort_by_cell(item_cell, kCells);
    const std::vector<float> sums = sum_by_cell(sorted, 0.0f, item_power);
    std::vector<float> reference(kCells, 0.0f);
    for (uint64_t i = 0; i < kItems; ++i)
        if (item_cell[i] != kNoCell) reference[item_cell[i]] += item_power(uint32_t(i));
    for (uint32_t c = 0; c < kCells; ++c) EXPECT_EQ(sums[c], reference[c]) << "cell " << c;
    EXPECT_EQ(sums[3], 0.0f);
}

// A grid with more cells than kMaxHistogramEntries / blocks takes fewer blocks; still the
// reference's result.
TEST(CellSort, ManyCellsUseFewerBlocksWithTheSameResult) {
    const uint32_t cells = uint32_t(kMaxHistogramEntries / 2 + 1);  // one block
    std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 14);
    for (uint64_t i = 0; i < kItems; i += 5)
        if (item_cell[i] != kNoCell) item_cell[i] = cells - 1 - item_cell[i];
    const ItemsByCell sorted = sort_by_cell(item_cell, cells);
    // Compare with the reference on the cells actually used (the reference is O(cells × items)).
    std::map<uint32_t, std::vector<uint32_t>> expected;
    for (uint64_t i = 0; i < kItems; ++i)
        if (item_cell[i] != kNoCell) expected[item_cell[i]].push_back(uint32_t(i));
    ASSERT_EQ(sorted.cell_count(), size_t(cells));
    for (uint32_t c = 0; c < cells; ++c) {
        const auto found = expected.find(c);
        if (found == expected.end()) {
            ASSERT_EQ(sorted.count(c), 0u) << "cell " << c;
            continue;
        }
        const std::vector<uint32_t> items(sorted.items(c), sorted.items(c) + sorted.count(c));
        ASSERT_EQ(items, found->second) << "cell " << c;
    }
}

TEST(CellSort, EmptyInputAndCellsWithoutItems) {
    const ItemsByCell none = sort_by_cell({}, 5);
    EXPECT_EQ(none.start, std::vector<uint32_t>(6, 0));
    EXPECT_TRUE(none.order.empty());
    int visited = 0;
    for_each_cell(none, [&](size_t, const uint32_t*, uint32_t) { ++visited; });
    EXPECT_EQ(visited, 0);
    EXPECT_EQ(sum_by_cell(none, 2.5f, item_power), std::vector<float>(5, 2.5f));

    const ItemsByCell no_cells = sort_by_cell({kNoCell, kNoCell}, 0);
    EXPECT_EQ(no_cells.start, std::vector<uint32_t>{0});
    EXPECT_TRUE(no_cells.order.empty());

    // Only cells 1 and 3 of 5 hold items; for_each_cell visits exactly those.
    const ItemsByCell sparse = sort_by_cell({3, kNoCell, 1, 3}, 5);
    EXPECT_EQ(sparse.start, (std::vector<uint32_t>{0, 0, 1, 1, 3, 3}));
    EXPECT_EQ(sparse.order, (std::vector<uint32_t>{2, 0, 3}));
    std::vector<size_t> cells_visited;
    for_each_cell(sparse, [&](size_t cell, const uint32_t*, uint32_t) {
        cells_visited.push_back(cell);  // one thread here: the sparse grid is a single chunk
    });
    EXPECT_EQ(cells_visited, (std::vector<size_t>{1, 3}));
}

TEST(CellSort, RefusesCellOutOfRangeNamingIt) {
    std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 15);
    const uint64_t bad = 2 * kCellSortItemsPerBlock + 17;  // in the third block
    item_cell[bad] = kCells;
    item_cell[kItems - 1] = kCells + 9;  // a later one: the first is reported
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        testing::expect_error<InvalidArgument>(
            [&] { sort_by_cell(item_cell, kCells); },
            {"item_cell[" + std::to_string(bad) + "] = " + std::to_string(kCells),
             "cells = " + std::to_string(kCells)});
    }
}

TEST(CellSort, CancelThrowsCancelled) {
    const std::vector<uint32_t> item_cell = random_cells(kItems, kCells, 16);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(sort_by_cell(item_cell, kCells, &progress), Cancelled);
    const ItemsByCell sorted = sort_by_cell(item_cell, kCells);
    EXPECT_THROW(sum_by_cell(sorted, 0.0f, item_power, &progress), Cancelled);
}

}  // namespace
}  // namespace shgi
