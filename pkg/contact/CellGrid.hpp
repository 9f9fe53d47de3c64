// Cell list with linked lists (seed paper §4.2): items are binned by a
// reference point into cubic cells of side L; a query visits the cells
// overlapping its box.  Cells live in a hash table sized to the item count, so
// memory is O(items) however far apart the pieces are.  Items remember their
// cell, so two cells sharing a bucket never make an item appear twice.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "CellHash.hpp"

namespace qdem {

class CellGrid {
public:
    // Rebuilds the grid for n items at points (3 per item).  No allocation
    // once the capacity has grown to the largest n seen.
    void build(const double* points, int32_t n, double cellSize) {
        head_.assign(h_.reset(cellSize, static_cast<std::size_t>(n)), -1);
        next_.resize(n);
        cx_.resize(n), cy_.resize(n), cz_.resize(n);
        for (int32_t i = 0; i < n; ++i) {
            const int64_t x = coord(points[3 * i]), y = coord(points[3 * i + 1]), z = coord(points[3 * i + 2]);
            cx_[i] = x, cy_[i] = y, cz_[i] = z;
            const std::size_t h = hash(x, y, z);
            next_[i] = head_[h];
            head_[h] = i;
        }
    }

    // Calls f(item) for every item binned in a cell that overlaps the box
    // [lo, hi]: with a box of half-width one cell, 8 cells instead of 27.
    template <class F>
    void forRange(const double* lo, const double* hi, F&& f) const {
        const int64_t x0 = coord(lo[0]), x1 = coord(hi[0]), y0 = coord(lo[1]), y1 = coord(hi[1]);
        const int64_t z0 = coord(lo[2]), z1 = coord(hi[2]);
        for (int64_t i = x0; i <= x1; ++i)
            for (int64_t j = y0; j <= y1; ++j)
                for (int64_t k = z0; k <= z1; ++k)
                    for (int32_t it = head_[hash(i, j, k)]; it >= 0; it = next_[it])
                        if (cx_[it] == i && cy_[it] == j && cz_[it] == k) f(it);
    }

private:
    int64_t coord(double v) const { return h_.coord(v); }
    std::size_t hash(int64_t x, int64_t y, int64_t z) const { return h_(x, y, z); }

    CellHash h_;
    std::vector<int32_t> head_, next_;
    std::vector<int64_t> cx_, cy_, cz_;
};

}  // namespace qdem
