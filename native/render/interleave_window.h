// The window of an interleaved-set filter (seed 004 §3; IndirectField::Interleave): element
// (x, y) of a grid (pixels, lightmap texels) whose element (u, v) holds set
// (u mod sets_x, v mod sets_y) alone. Every set is an estimate of all the light; the filter's
// answer is the mean over the sets, each set read at its nearest elements that join the centre
// (same surface, by the caller's test).
//
// Within a full window this is the paper's filter exactly: for an even period the nearest
// elements of the end sets are the two (or four) at offsets ±n/2, averaged, which is the
// half-weight end taps of Interleave::tap_weight. Where the window is cut — a UV chart's edge, a
// fold — the paper's window drops the sets beyond the cut and weighs the rest unevenly; here a
// set cut off is read instead at its next element on the near side, up to a full period away,
// so every element keeps every set at weight 1 (a lightmap texel at a chart's edge sees all the
// light). Used by bakes (bake/lightmap_baker.cpp). The preview's screen-space stage keeps the
// paper's window: there this window lowered the relative RMSE against brute force only from
// 0.130 to 0.129 and raised the largest per-phase residual from 2.1% to 3.2%
// (tests/python/test_instant_gi.py, the normal-mapped floor).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace shgi {

class InterleaveWindow {
  public:
    InterleaveWindow(int sets_x, int sets_y)
        : sets_x_(sets_x), sets_y_(sets_y), side_x_(2 * sets_x + 1), side_y_(2 * sets_y + 1),
          joined_(size_t(side_x_) * size_t(side_y_)), best_(size_t(sets_x) * size_t(sets_y)),
          count_(best_.size()) {}

    // Visits the taps of element (x, y) of a width × height grid: add(u, v, weight) for each
    // element read, the weights of each set summing to 1 / (the sets read), so the weighted sum
    // is the mean over sets. joins(u, v) says whether element (u, v) (in the grid, not the
    // centre) lies on the centre's surface. Deterministic: taps in row-major order.
    template <class Joins, class Add>
    void visit(int x, int y, int width, int height, Joins&& joins, Add&& add) {
        std::fill(best_.begin(), best_.end(), kNone);
        std::fill(count_.begin(), count_.end(), 0);
        for (int dy = -sets_y_; dy <= sets_y_; ++dy)
            for (int dx = -sets_x_; dx <= sets_x_; ++dx) {
                const int u = x + dx, v = y + dy;
                uint8_t& joined = joined_[tap(dx, dy)];
                joined = u >= 0 && u < width && v >= 0 && v < height &&
                         ((dx == 0 && dy == 0) || joins(u, v));
                if (!joined) continue;
                const size_t set = set_of(u, v);
                const int d2 = dx * dx + dy * dy;
                if (d2 < best_[set]) best_[set] = d2, count_[set] = 0;
                if (d2 == best_[set]) ++count_[set];
            }
        int sets = 0;
        for (int c : count_) sets += c > 0;
        for (int dy = -sets_y_; dy <= sets_y_; ++dy)
            for (int dx = -sets_x_; dx <= sets_x_; ++dx) {
                if (!joined_[tap(dx, dy)]) continue;
                const int u = x + dx, v = y + dy;
                const size_t set = set_of(u, v);
                if (dx * dx + dy * dy != best_[set]) continue;
                add(u, v, 1.0f / float(count_[set] * sets));
            }
    }

    // How far (elements) the window reaches from its centre along x and y.
    static int reach(int sets) { return sets; }

  private:
    static constexpr int kNone = 1 << 30;
    size_t tap(int dx, int dy) const {
        return size_t(dy + sets_y_) * size_t(side_x_) + size_t(dx + sets_x_);
    }
    size_t set_of(int u, int v) const {
        return size_t(v % sets_y_) * size_t(sets_x_) + size_t(u % sets_x_);
    }

    int sets_x_, sets_y_, side_x_, side_y_;
    std::vector<uint8_t> joined_;
    std::vector<int> best_, count_;
};

}  // namespace shgi
