// Grouping items by cell: a parallel, stable counting sort of item indices by cell index, and
// per-cell passes over its result without atomics.
//
// The shared groundwork of the grid methods (seed 001 §3.2–3.3, Fig. 3: photons are bucketed
// into the cells of a grid before each cell's radiance is estimated; seed 000 §5.3 does the same
// for lattice injection). Items are numbered 0 .. n − 1 (photons, texels, VPLs); item i lies in
// cell item_cell[i], or in none when item_cell[i] == kNoCell (it is left out).
//
// The sort is stable: the items of a cell keep their input order, so the result is a function of
// the input alone (never of the thread count or the block split) and a reduction that walks a
// cell's items in order is bit-identical for any thread count. It runs in three passes:
//   1. per block of items (fixed size, the last one shorter) a histogram of its cells;
//   2. per cell, the exclusive prefix sum over cells of the totals gives where the cell starts
//      in the output, and a running sum over blocks turns each block's count into the position
//      where that block writes its first item of the cell;
//   3. per block, in input order, each item is written at its block's next position for its cell.
// The histograms take (blocks × cells) counters, so the number of blocks shrinks as the cell
// count grows (kMaxHistogramEntries); a grid of millions of cells sorts with a single block,
// i.e. serially, exactly like the reference counting sort.
//
// for_each_cell / sum_by_cell then hand each cell to one thread, which visits the cell's items in
// input order: sums come out in a fixed order, with no atomics and no per-thread partial sums.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "util/memory.h"
#include "util/parallel.h"
#include "util/progress.h"

namespace shgi {

// item_cell value of an item that lies in no cell; also the bound on cell counts and item counts.
inline constexpr uint32_t kNoCell = std::numeric_limits<uint32_t>::max();

// Item indices grouped by cell: the items of cell c are order[start[c]] .. order[start[c + 1] − 1],
// in increasing (input) order.
struct ItemsByCell {
    std::vector<uint32_t> start;  // cell count + 1 entries; start[0] = 0
    std::vector<uint32_t> order;  // the indices of the items that lie in a cell

    size_t cell_count() const { return start.empty() ? 0 : start.size() - 1; }
    uint32_t count(size_t cell) const { return start[cell + 1] - start[cell]; }
    const uint32_t* items(size_t cell) const { return order.data() + start[cell]; }
};

// Sorting tunables. The block size only sets how the first and last passes are split among
// threads; the result does not depend on it.
inline constexpr uint64_t kCellSortItemsPerBlock = uint64_t(1) << 16;
// At most this many histogram counters (blocks × cells) at once, 64 MB: larger grids use fewer
// blocks, down to one.
inline constexpr uint64_t kMaxHistogramEntries = uint64_t(1) << 24;
// Cells per parallel chunk in the per-cell passes.
inline constexpr uint64_t kCellSortCellsPerChunk = 512;

// Groups the items by cell (stable counting sort, see above). `cells` is the number of cells;
// every item_cell[i] must be < cells or kNoCell. Throws InvalidArgument naming the first item
// whose cell is out of range (and its value), or when cells or item_cell.size() reach kNoCell;
// OutOfMemory (before allocating) when the output and histograms do not fit; Cancelled when
// `progress` is cancelled (polled between blocks; progress is not reported, it belongs to the
// caller's stage).
ItemsByCell sort_by_cell(const std::vector<uint32_t>& item_cell, size_t cells,
                         const Progress* progress = nullptr);

// Calls body(cell, items, count) for every cell holding at least one item, each cell on one
// thread, its items (indices) in input order. Cells are handed out in chunks of kCellSortCellsPerChunk;
// cancel is polled before every cell (one cell may hold millions of items) and the progress is
// reported per chunk. Throws Cancelled after a cancel, once the running cells finish.
template <typename Body>
void for_each_cell(const ItemsByCell& sorted, Body&& body, Progress* progress = nullptr) {
    parallel_for(
        0, sorted.cell_count(), kCellSortCellsPerChunk,
        [&](uint64_t begin, uint64_t end) {
            for (uint64_t cell = begin; cell < end; ++cell) {
                throw_if_cancelled(progress);
                const uint32_t count = sorted.count(cell);
                if (count > 0) body(size_t(cell), sorted.items(cell), count);
            }
        },
        progress);
}

// Per cell, zero + value(i₀) + value(i₁) + … over the cell's items i₀ < i₁ < … in that order
// (T needs operator+=): bit-identical for any thread count. Cells without items get `zero`.
// The result's memory is checked first (OutOfMemory naming `what`).
template <typename T, typename Value>
std::vector<T> sum_by_cell(const ItemsByCell& sorted, const T& zero, Value&& value,
                           Progress* progress = nullptr, const char* what = "sum_by_cell") {
    require_memory(saturating_mul(sorted.cell_count(), sizeof(T)),
                   format_message(what, ": per-cell sums of ", sorted.cell_count(), " cells"),
                   "use fewer cells");
    std::vector<T> sums(sorted.cell_count(), zero);
    for_each_cell(
        sorted,
        [&](size_t cell, const uint32_t* items, uint32_t count) {
            T sum = zero;
            for (uint32_t k = 0; k < count; ++k) sum += value(items[k]);
            sums[cell] = sum;
        },
        progress);
    return sums;
}

}  // namespace shgi
