// Cell list (seed paper §4.2): items are binned by a reference point into
// cubic cells of side L; a query visits the cells overlapping its box.  The
// items are stored cell by cell in one packed array (CellBins: a counting sort
// by cell, memory O(items) however far apart the pieces are), their points
// and bounding radii beside them (struct of arrays), so a query reads each
// cell's items contiguously: one run per (x, y) column of cells in the usual
// dense case.  Within a cell the items come in descending order (the order
// of the linked chains this layout replaced; the Verlet lists built from the
// queries, and the contact forces summed from those, depend on it), and the
// cells are visited in x-y-z order.
#pragma once
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
        bins_.setCellSize(cellSize);
        cell_.resize(3 * static_cast<std::size_t>(n));
        for (std::size_t k = 0; k < cell_.size(); ++k) cell_[k] = bins_.coord(points[k]);
        item_.resize(n), x_.resize(n), y_.resize(n), z_.resize(n), r_.resize(n);
        bins_.build(cell_.data(), n, cellSize, [&](int32_t s, int32_t i) {
            item_[s] = i;
            x_[s] = points[3 * i], y_[s] = points[3 * i + 1], z_[s] = points[3 * i + 2];
            r_[s] = radius ? radius[i] : 0.0;
        });
    }

    // Calls f(b, e) for runs [b, e) of packed slots that together hold, in
    // visiting order, the items binned in the cells overlapping the box
    // [lo, hi]: with a box of half-width one cell, 8 cells instead of 27.
    // Slot s holds item()[s] at (x()[s], y()[s], z()[s]) with radius r()[s].
    template <class F>
    void forRuns(const double* lo, const double* hi, F&& f) const {
        int64_t a[3], b[3];
        for (int d = 0; d < 3; ++d) a[d] = bins_.coord(lo[d]), b[d] = bins_.coord(hi[d]);
        bins_.forRuns(a, b, f);
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

    bool dense() const { return bins_.dense(); }  // the last build's indexing (CellBins)

private:
    CellBins bins_;
    std::vector<int64_t> cell_;          // per item: its cell (while building)
    std::vector<int32_t> item_;          // packed: cell by cell, descending items within a cell
    std::vector<double> x_, y_, z_, r_;  // packed alike: points and radii
};

}  // namespace qdem
