// Cell list for elongated items (surface edges): each item is entered in every
// cell its bounding box touches, and a query visits only the cells of its own
// box.  Two items are near each other only if their boxes share a cell; the
// pair is reported once, in the shared cell holding the low corner of the
// boxes' intersection.  With cells about one edge long an edge sits in at most
// 8 cells, and a query meets far fewer strangers than the 27-cell block of
// CellGrid would.
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
        h_.inv = 1.0 / cellSize;  // cell coordinates are needed to count the entries
        lo_.assign(lo, lo + 3 * n);
        hi_.assign(hi, hi + 3 * n);
        std::size_t entries = 0;
        for (int32_t i = 0; i < n; ++i) {
            std::size_t c = 1;
            for (int d = 0; d < 3; ++d) c *= static_cast<std::size_t>(coord(hi[3 * i + d]) - coord(lo[3 * i + d]) + 1);
            entries += c;
        }
        head_.assign(h_.reset(cellSize, entries), -1);
        item_.resize(entries), next_.resize(entries), cx_.resize(entries), cy_.resize(entries), cz_.resize(entries);
        int32_t k = 0;
        for (int32_t i = 0; i < n; ++i)
            forCells(&lo[3 * i], &hi[3 * i], [&](int64_t x, int64_t y, int64_t z) {
                const std::size_t h = hash(x, y, z);
                item_[k] = i, cx_[k] = x, cy_[k] = y, cz_[k] = z, next_[k] = head_[h];
                head_[h] = k++;
            });
    }

    // Calls f(j) once for every item j whose box overlaps the box [lo, hi].
    template <class F>
    void forOverlapping(const double* lo, const double* hi, F&& f) const {
        forCells(lo, hi, [&](int64_t x, int64_t y, int64_t z) {
            for (int32_t k = head_[hash(x, y, z)]; k >= 0; k = next_[k]) {
                if (cx_[k] != x || cy_[k] != y || cz_[k] != z) continue;
                const int32_t j = item_[k];
                const double* a = &lo_[3 * j];
                const double* b = &hi_[3 * j];
                bool overlap = true;
                int64_t c[3];
                for (int d = 0; d < 3 && overlap; ++d) {
                    overlap = a[d] <= hi[d] && lo[d] <= b[d];
                    c[d] = coord(std::max(a[d], lo[d]));  // low corner of the intersection
                }
                if (overlap && c[0] == x && c[1] == y && c[2] == z) f(j);
            }
        });
    }

private:
    int64_t coord(double v) const { return h_.coord(v); }
    std::size_t hash(int64_t x, int64_t y, int64_t z) const { return h_(x, y, z); }
    template <class F>
    void forCells(const double* lo, const double* hi, F&& f) const {
        const int64_t x0 = coord(lo[0]), x1 = coord(hi[0]), y0 = coord(lo[1]), y1 = coord(hi[1]);
        const int64_t z0 = coord(lo[2]), z1 = coord(hi[2]);
        for (int64_t x = x0; x <= x1; ++x)
            for (int64_t y = y0; y <= y1; ++y)
                for (int64_t z = z0; z <= z1; ++z) f(x, y, z);
    }

    CellHash h_;
    std::vector<double> lo_, hi_;
    std::vector<int32_t> head_, item_, next_;
    std::vector<int64_t> cx_, cy_, cz_;
};

}  // namespace qdem
