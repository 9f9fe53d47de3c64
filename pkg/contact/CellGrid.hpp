// Cell list (seed paper §4.2): items are binned by a reference point into
// cubic cells of side L; a query visits the cells overlapping its box.  The
// items are stored cell by cell in one packed array (a counting sort by
// cell), their points and bounding radii beside them (struct of arrays), so
// a query reads each cell's items contiguously.
//
// Two indexings of the cells, chosen per build: when the occupied cells'
// bounding block has at most 4 n + 64 cells, a dense block (cell offsets in
// x-y-z order: the z cells of one (x, y) column are one contiguous run, so a
// query of 2 x 2 x 2 cells reads 4 runs); otherwise a table of the occupied
// cells (CellTable: memory O(items) however far apart the pieces are).
//
// Within a cell the items come in descending order (the order of the linked
// chains this layout replaced; the Verlet lists built from the queries, and
// the contact forces summed from those, depend on it), and the cells are
// visited in x-y-z order.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "CellHash.hpp"

namespace qdem {

class CellGrid {
public:
    // Rebuilds the grid for n items at points (3 per item), with bounding
    // radii (1 per item; none: 0).  No allocation once the capacity has grown
    // to the largest n seen.
    void build(const double* points, int32_t n, double cellSize, const double* radius = nullptr) {
        t_.setCellSize(cellSize);
        cell_.resize(3 * static_cast<std::size_t>(n));
        int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
        for (int32_t i = 0; i < n; ++i)
            for (int d = 0; d < 3; ++d) {
                const int64_t c = t_.coord(points[3 * i + d]);
                cell_[3 * i + d] = c;
                lo[d] = i == 0 ? c : std::min(lo[d], c), hi[d] = i == 0 ? c : std::max(hi[d], c);
            }
        // Dense when the block is small (each extent checked first: no overflow).
        const int64_t limit = 4 * static_cast<int64_t>(n) + 64;
        dense_ = true;
        int64_t cells = 1;
        for (int d = 0; d < 3; ++d) {
            const int64_t e = hi[d] - lo[d] + 1;
            dense_ = dense_ && e >= 0 && e <= limit;
            if (dense_) cells *= e;
            dense_ = dense_ && cells <= limit;
            lo_[d] = lo[d], dim_[d] = e;
        }
        item_.resize(n), x_.resize(n), y_.resize(n), z_.resize(n), r_.resize(n);
        if (dense_) {
            start_.assign(static_cast<std::size_t>(cells) + 1, 0);
            for (int32_t i = 0; i < n; ++i) ++start_[denseIndex(&cell_[3 * i]) + 1];
            for (std::size_t c = 0; c + 1 < start_.size(); ++c) start_[c + 1] += start_[c];
            fill_.assign(start_.begin() + 1, start_.end());  // filled from each cell's end, item n-1 last
            for (int32_t i = 0; i < n; ++i) put(--fill_[denseIndex(&cell_[3 * i])], i, points, radius);
        } else {
            t_.reset(cellSize, static_cast<std::size_t>(n));
            for (int32_t i = 0; i < n; ++i) t_.note(i, cell_[3 * i], cell_[3 * i + 1], cell_[3 * i + 2]);
            t_.pack();
            for (int32_t i = n - 1; i >= 0; --i) put(t_.place(i), i, points, radius);
        }
    }

    // Calls f(b, e) for runs [b, e) of packed slots that together hold, in
    // visiting order, the items binned in the cells overlapping the box
    // [lo, hi]: with a box of half-width one cell, 8 cells instead of 27.
    // Slot s holds item(s) at (x(s), y(s), z(s)) with radius r(s).
    template <class F>
    void forRuns(const double* lo, const double* hi, F&& f) const {
        int64_t a[3], b[3];
        for (int d = 0; d < 3; ++d) a[d] = t_.coord(lo[d]), b[d] = t_.coord(hi[d]);
        if (dense_) {
            for (int d = 0; d < 3; ++d) {
                a[d] = std::max(a[d], lo_[d]) - lo_[d], b[d] = std::min(b[d], lo_[d] + dim_[d] - 1) - lo_[d];
                if (a[d] > b[d]) return;
            }
            for (int64_t i = a[0]; i <= b[0]; ++i)
                for (int64_t j = a[1]; j <= b[1]; ++j) {
                    const std::size_t c = static_cast<std::size_t>((i * dim_[1] + j) * dim_[2]);
                    const int32_t s0 = start_[c + a[2]], s1 = start_[c + b[2] + 1];
                    if (s0 < s1) f(s0, s1);
                }
            return;
        }
        for (int64_t i = a[0]; i <= b[0]; ++i)
            for (int64_t j = a[1]; j <= b[1]; ++j)
                for (int64_t k = a[2]; k <= b[2]; ++k) {
                    int32_t s0, s1;
                    if (t_.find(i, j, k, s0, s1)) f(s0, s1);
                }
    }

    // Calls f(item) for every item binned in a cell that overlaps the box.
    template <class F>
    void forRange(const double* lo, const double* hi, F&& f) const {
        forRuns(lo, hi, [&](int32_t b, int32_t e) {
            for (int32_t s = b; s < e; ++s) f(item_[s]);
        });
    }

    const int32_t* item() const { return item_.data(); }
    const double* x() const { return x_.data(); }
    const double* y() const { return y_.data(); }
    const double* z() const { return z_.data(); }
    const double* r() const { return r_.data(); }

private:
    std::size_t denseIndex(const int64_t* c) const {
        return static_cast<std::size_t>(((c[0] - lo_[0]) * dim_[1] + (c[1] - lo_[1])) * dim_[2] + (c[2] - lo_[2]));
    }
    void put(int32_t s, int32_t i, const double* points, const double* radius) {
        item_[s] = i;
        x_[s] = points[3 * i], y_[s] = points[3 * i + 1], z_[s] = points[3 * i + 2];
        r_[s] = radius ? radius[i] : 0.0;
    }

    CellTable t_;
    bool dense_ = true;
    int64_t lo_[3] = {0, 0, 0}, dim_[3] = {0, 0, 0};  // dense block: lowest cell and extent
    std::vector<int32_t> start_, fill_;              // dense block: packed offset of each cell (+ end)
    std::vector<int64_t> cell_;                      // per item: its cell (while building)
    std::vector<int32_t> item_;                      // packed: cell by cell, descending items within a cell
    std::vector<double> x_, y_, z_, r_;              // packed alike: points and radii
};

}  // namespace qdem
