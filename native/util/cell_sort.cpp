#include "util/cell_sort.h"

#include <algorithm>

#include "util/error.h"

namespace shgi {
namespace {

// Blocks the items are split into: one per kCellSortItemsPerBlock items, fewer when the
// histograms would exceed kMaxHistogramEntries. Depends on the input sizes only.
uint64_t block_count(uint64_t items, uint64_t cells) {
    const uint64_t by_items = (items + kCellSortItemsPerBlock - 1) / kCellSortItemsPerBlock;
    const uint64_t by_memory = kMaxHistogramEntries / std::max<uint64_t>(cells, 1);
    return std::max<uint64_t>(1, std::min(by_items, by_memory));
}

}  // namespace

ItemsByCell sort_by_cell(const std::vector<uint32_t>& item_cell, size_t cells,
                         const Progress* progress) {
    const uint64_t n = item_cell.size();
    if (cells >= kNoCell)
        throw InvalidArgument(format_message("sort_by_cell: cells = ", cells,
                                             " must be less than ", kNoCell));
    if (n >= kNoCell)
        throw InvalidArgument(format_message("sort_by_cell: item_cell holds ", n,
                                             " items; pass fewer than ", kNoCell));
    throw_if_cancelled(progress);
    const uint64_t blocks = block_count(n, cells);
    const uint64_t block_size = (n + blocks - 1) / std::max<uint64_t>(blocks, 1);
    const uint64_t counters = saturating_mul(blocks, cells);
    require_memory(
        saturating_mul(saturating_add(saturating_add(n, cells + 1), counters), sizeof(uint32_t)),
        format_message("sort_by_cell: ", n, " items in ", cells, " cells"),
        "use fewer cells or sort fewer items at once");

    // Calls slice(i0, i1) over block b's items in slices of kCellSortItemsPerBlock, polling
    // cancel before each: a single block (a grid of many cells) may hold every item.
    const auto for_each_block_slice = [&](uint64_t b, auto&& slice) {
        const uint64_t begin = std::min(n, b * block_size);
        const uint64_t end = std::min(n, begin + block_size);
        for_each_slice(end - begin, kCellSortItemsPerBlock, progress,
                       [&](uint64_t s0, uint64_t s1) { slice(begin + s0, begin + s1); });
    };
    // histogram[b * cells + c]: first the items of block b in cell c, then (pass 2) the position
    // where block b writes its next item of cell c.
    std::vector<uint32_t> histogram(counters, 0);
    std::vector<uint64_t> first_bad(blocks, n);  // per block, the first item out of range
    // Parallel passes poll cancel by hand: progress belongs to the caller's stage.
    parallel_for(0, blocks, 1, [&](uint64_t b0, uint64_t b1) {
        for (uint64_t b = b0; b < b1; ++b) {
            uint32_t* counts = histogram.data() + b * cells;
            for_each_block_slice(b, [&](uint64_t i0, uint64_t i1) {
                for (uint64_t i = i0; i < i1 && first_bad[b] == n; ++i) {
                    const uint32_t cell = item_cell[i];
                    if (cell == kNoCell) continue;
                    if (cell >= cells) first_bad[b] = i;
                    else ++counts[cell];
                }
            });
        }
    });
    // The first bad item of the earliest block that has one: the same whatever the split.
    for (uint64_t b = 0; b < blocks; ++b)
        if (first_bad[b] < n)
            throw InvalidArgument(format_message(
                "sort_by_cell: item_cell[", first_bad[b], "] = ", item_cell[first_bad[b]],
                " is not a cell index below cells = ", cells, " (nor kNoCell)"));

    ItemsByCell sorted;
    sorted.start.assign(cells + 1, 0);
    // Totals per cell (over blocks, parallel over cells), then their exclusive prefix sum.
    parallel_for(0, cells, kCellSortCellsPerChunk, [&](uint64_t c0, uint64_t c1) {
        throw_if_cancelled(progress);
        for (uint64_t c = c0; c < c1; ++c) {
            uint32_t total = 0;
            for (uint64_t b = 0; b < blocks; ++b) total += histogram[b * cells + c];
            sorted.start[c + 1] = total;
        }
    });
    for_each_slice(cells, kCellSortItemsPerBlock, progress, [&](uint64_t c0, uint64_t c1) {
        for (uint64_t c = c0; c < c1; ++c) sorted.start[c + 1] += sorted.start[c];
    });
    // Each block's first position in each cell: the cell's start plus the earlier blocks' items.
    parallel_for(0, cells, kCellSortCellsPerChunk, [&](uint64_t c0, uint64_t c1) {
        throw_if_cancelled(progress);
        for (uint64_t c = c0; c < c1; ++c) {
            uint32_t position = sorted.start[c];
            for (uint64_t b = 0; b < blocks; ++b) {
                uint32_t& entry = histogram[b * cells + c];
                const uint32_t count = entry;
                entry = position;
                position += count;
            }
        }
    });
    // Scatter: within a block items go in input order, and blocks fill each cell in block order,
    // so each cell ends up in input order.
    sorted.order.resize(sorted.start[cells]);
    parallel_for(0, blocks, 1, [&](uint64_t b0, uint64_t b1) {
        for (uint64_t b = b0; b < b1; ++b) {
            uint32_t* next = histogram.data() + b * cells;
            for_each_block_slice(b, [&](uint64_t i0, uint64_t i1) {
                for (uint64_t i = i0; i < i1; ++i) {
                    const uint32_t cell = item_cell[i];
                    if (cell != kNoCell) sorted.order[next[cell]++] = uint32_t(i);
                }
            });
        }
    });
    return sorted;
}

}  // namespace shgi
