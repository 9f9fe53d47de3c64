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
        t_.setCellSize(cellSize);  // cell coordinates are needed to count the entries
        std::size_t entries = 0;
        for (int32_t i = 0; i < n; ++i) entries += cellCount(&lo[3 * i], &hi[3 * i]);
        t_.reset(cellSize, entries);
        int32_t k = 0;
        for (int32_t i = 0; i < n; ++i)
            forCells(&lo[3 * i], &hi[3 * i], [&](int64_t x, int64_t y, int64_t z) { t_.note(k++, x, y, z); });
        t_.pack();
        // Entries packed cell by cell, in descending entry order within a cell
        // (entries are numbered item after item), each with its item's box.
        item_.resize(entries), box_.resize(6 * entries);
        for (int32_t i = n - 1; i >= 0; --i) {
            const auto c = static_cast<int32_t>(cellCount(&lo[3 * i], &hi[3 * i]));
            for (int32_t e = k - 1; e >= k - c; --e) {
                const int32_t p = t_.place(e);
                item_[p] = i;
                double* b = &box_[6 * static_cast<std::size_t>(p)];
                for (int d = 0; d < 3; ++d) b[d] = lo[3 * i + d], b[3 + d] = hi[3 * i + d];
            }
            k -= c;
        }
    }

    // Calls f(j) once for every item j whose box overlaps the box [lo, hi].
    template <class F>
    void forOverlapping(const double* lo, const double* hi, F&& f) const {
        forCells(lo, hi, [&](int64_t x, int64_t y, int64_t z) {
            int32_t b, e;
            if (!t_.find(x, y, z, b, e)) return;
            for (int32_t k = b; k < e; ++k) {
                const double* a = &box_[6 * static_cast<std::size_t>(k)];  // the item's lo, then hi
                bool overlap = true;
                int64_t c[3];
                for (int d = 0; d < 3 && overlap; ++d) {
                    overlap = a[d] <= hi[d] && lo[d] <= a[3 + d];
                    c[d] = t_.coord(std::max(a[d], lo[d]));  // low corner of the intersection
                }
                if (overlap && c[0] == x && c[1] == y && c[2] == z) f(item_[k]);
            }
        });
    }

private:
    std::size_t cellCount(const double* lo, const double* hi) const {
        std::size_t c = 1;
        for (int d = 0; d < 3; ++d) c *= static_cast<std::size_t>(t_.coord(hi[d]) - t_.coord(lo[d]) + 1);
        return c;
    }
    template <class F>
    void forCells(const double* lo, const double* hi, F&& f) const {
        const int64_t x0 = t_.coord(lo[0]), x1 = t_.coord(hi[0]), y0 = t_.coord(lo[1]), y1 = t_.coord(hi[1]);
        const int64_t z0 = t_.coord(lo[2]), z1 = t_.coord(hi[2]);
        for (int64_t x = x0; x <= x1; ++x)
            for (int64_t y = y0; y <= y1; ++y)
                for (int64_t z = z0; z <= z1; ++z) f(x, y, z);
    }

    CellTable t_;
    std::vector<int32_t> item_;  // packed entries: cell by cell, descending entry order within a cell
    std::vector<double> box_;    // packed alike: each entry's item box (lo, hi: 6)
};

}  // namespace qdem
