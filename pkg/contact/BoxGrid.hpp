// Cell list for elongated items (surface edges): each item is entered in every
// cell its bounding box touches, and a query visits only the cells of its own
// box.  Two items are near each other only if their boxes share a cell; the
// pair is reported once, in the shared cell holding the low corner of the
// boxes' intersection.  With cells about one edge long an edge sits in at most
// 8 cells, and a query meets far fewer strangers than the 27-cell block of
// CellGrid would.  The entries are packed cell by cell (CellTable), each with
// its item's box, so a query reads a cell's entries contiguously.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "CellHash.hpp"

namespace qdem {

class BoxGrid {
public:
    // n items with boxes lo/hi (3 each).  No allocation once grown.
    void build(const double* lo, const double* hi, int32_t n, double cellSize) {
        bins_.setCellSize(cellSize);  // cell coordinates are needed to count the entries
        // One entry per (item, cell of its box), numbered item after item.
        cell_.clear(), entryItem_.clear();
        for (int32_t i = 0; i < n; ++i)
            forCells(&lo[3 * i], &hi[3 * i], [&](int64_t x, int64_t y, int64_t z) {
                cell_.insert(cell_.end(), {x, y, z});
                entryItem_.push_back(i);
            });
        const auto entries = static_cast<int32_t>(entryItem_.size());
        item_.resize(entries), box_.resize(6 * static_cast<std::size_t>(entries));
        bins_.build(cell_.data(), entries, cellSize, [&](int32_t s, int32_t e) {
            const int32_t i = entryItem_[e];
            item_[s] = i;
            double* b = &box_[6 * static_cast<std::size_t>(s)];
            for (int d = 0; d < 3; ++d) b[d] = lo[3 * i + d], b[3 + d] = hi[3 * i + d];
        });
    }

    // Calls f(j) once for every item j whose box overlaps the box [lo, hi].
    template <class F>
    void forOverlapping(const double* lo, const double* hi, F&& f) const {
        int64_t a[3], b[3];
        for (int d = 0; d < 3; ++d) a[d] = bins_.coord(lo[d]), b[d] = bins_.coord(hi[d]);
        bins_.forCells(a, b, [&](int64_t x, int64_t y, int64_t z, int32_t s0, int32_t s1) {
            for (int32_t k = s0; k < s1; ++k) {
                const double* q = &box_[6 * static_cast<std::size_t>(k)];  // the item's lo, then hi
                bool overlap = true;
                int64_t c[3];
                for (int d = 0; d < 3 && overlap; ++d) {
                    overlap = q[d] <= hi[d] && lo[d] <= q[3 + d];
                    c[d] = bins_.coord(std::max(q[d], lo[d]));  // low corner of the intersection
                }
                if (overlap && c[0] == x && c[1] == y && c[2] == z) f(item_[k]);
            }
        });
    }

    bool dense() const { return bins_.dense(); }  // the last build's indexing (CellBins)

private:
    template <class F>
    void forCells(const double* lo, const double* hi, F&& f) const {
        const int64_t x0 = bins_.coord(lo[0]), x1 = bins_.coord(hi[0]), y0 = bins_.coord(lo[1]), y1 = bins_.coord(hi[1]);
        const int64_t z0 = bins_.coord(lo[2]), z1 = bins_.coord(hi[2]);
        for (int64_t x = x0; x <= x1; ++x)
            for (int64_t y = y0; y <= y1; ++y)
                for (int64_t z = z0; z <= z1; ++z) f(x, y, z);
    }

    CellBins bins_;
    std::vector<int64_t> cell_;       // per entry: its cell (while building)
    std::vector<int32_t> entryItem_;  // per entry: its item (while building)
    std::vector<int32_t> item_;       // packed entries: cell by cell, descending entry order within a cell
    std::vector<double> box_;         // packed alike: each entry's item box (lo, hi: 6)
};

}  // namespace qdem
