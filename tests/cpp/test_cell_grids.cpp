// The cell lists (CellGrid, BoxGrid) against brute force: the items a query
// visits, and the order it visits them in (cells in x-y-z order, descending
// items within a cell: the Verlet lists, and so the contact force sums, are
// built in that order), for both indexings of CellBins: the dense block of
// cells and the hash table used when the occupied cells are far apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

#include "contact/BoxGrid.hpp"
#include "contact/CellGrid.hpp"

using namespace qdem;

namespace {

using Cell = std::array<int64_t, 3>;

// The grids' cell of a point: floor(x * (1 / L)) (not x / L, which differs
// for points on a cell boundary).
Cell cellOf(const double* p, double L) {
    const double inv = 1.0 / L;
    return {static_cast<int64_t>(std::floor(p[0] * inv)), static_cast<int64_t>(std::floor(p[1] * inv)),
            static_cast<int64_t>(std::floor(p[2] * inv))};
}

// n points in a few clusters; `spread` apart (in cells) puts the clusters far
// enough apart for the hash table (the dense block would exceed 4 n + 64 cells).
std::vector<double> points(std::mt19937& rng, int n, double L, double spread) {
    std::uniform_real_distribution<double> u(-3 * L, 3 * L);
    std::uniform_int_distribution<int> cluster(0, 2);
    std::vector<double> p(3 * n);
    for (int i = 0; i < n; ++i) {
        const int c = cluster(rng);
        for (int d = 0; d < 3; ++d) p[3 * i + d] = c * spread * L * (d == 0 ? 1 : 0.5) + u(rng);
    }
    // A few points exactly on cell boundaries (floor decides their cell).
    for (int i = 0; i < n / 10; ++i) p[3 * i] = std::round(p[3 * i] / L) * L;
    return p;
}

void checkCellGrid(double spread) {
    std::mt19937 rng(7);
    const double L = 0.37;
    const int n = 400;
    const std::vector<double> p = points(rng, n, L, spread);
    std::vector<double> r(n);
    for (int i = 0; i < n; ++i) r[i] = 0.01 * i;
    CellGrid g;
    g.build(p.data(), n, L, r.data());
    ASSERT_EQ(g.dense(), spread < 100);
    std::uniform_int_distribution<int> pick(0, n - 1);
    std::uniform_real_distribution<double> half(0.1 * L, 1.6 * L);
    for (int trial = 0; trial < 300; ++trial) {
        const double* c = &p[3 * pick(rng)];
        const double h = half(rng);
        const double lo[3] = {c[0] - h, c[1] - h, c[2] - h}, hi[3] = {c[0] + h, c[1] + 0.5 * h, c[2] + 2 * h};
        const Cell a = cellOf(lo, L), b = cellOf(hi, L);
        std::vector<int32_t> expected;
        for (int64_t x = a[0]; x <= b[0]; ++x)
            for (int64_t y = a[1]; y <= b[1]; ++y)
                for (int64_t z = a[2]; z <= b[2]; ++z)
                    for (int i = n - 1; i >= 0; --i)
                        if (cellOf(&p[3 * i], L) == Cell{x, y, z}) expected.push_back(i);
        std::vector<int32_t> got;
        g.forRange(lo, hi, [&](int32_t i) { got.push_back(i); });
        ASSERT_EQ(got, expected) << "trial " << trial;
        // The packed slots carry each item's point and radius.
        g.forRuns(lo, hi, [&](int32_t s0, int32_t s1) {
            for (int32_t s = s0; s < s1; ++s) {
                const int32_t i = g.item()[s];
                EXPECT_EQ(g.x()[s], p[3 * i]);
                EXPECT_EQ(g.y()[s], p[3 * i + 1]);
                EXPECT_EQ(g.z()[s], p[3 * i + 2]);
                EXPECT_EQ(g.r()[s], r[i]);
            }
        });
    }
    // Rebuilt empty: a query visits nothing.
    const double lo[3] = {-1e3, -1e3, -1e3}, hi[3] = {1e3, 1e3, 1e3};
    g.build(p.data(), 0, L);
    g.forRange(lo, hi, [&](int32_t) { ADD_FAILURE() << "empty grid visited an item"; });
}

void checkBoxGrid(double spread) {
    std::mt19937 rng(11);
    const double L = 0.5;
    const int n = 300;
    const std::vector<double> c = points(rng, n, L, spread);
    std::uniform_real_distribution<double> len(0.0, 0.6 * L);
    std::vector<double> lo(3 * n), hi(3 * n);
    for (int i = 0; i < 3 * n; ++i) {
        const double a = len(rng), b = len(rng);
        lo[i] = c[i] - a, hi[i] = c[i] + b;
    }
    BoxGrid g;
    g.build(lo.data(), hi.data(), n, L);
    ASSERT_EQ(g.dense(), spread < 100);
    for (int q = 0; q < n; ++q) {
        const double* ql = &lo[3 * q];
        const double* qh = &hi[3 * q];
        // Each overlapping item once, in the cell of the low corner of the
        // intersection: cells in x-y-z order, descending items within a cell.
        std::vector<std::tuple<Cell, int>> expected;
        for (int j = 0; j < n; ++j) {
            bool overlap = true;
            double corner[3];
            for (int d = 0; d < 3; ++d) {
                overlap = overlap && lo[3 * j + d] <= qh[d] && ql[d] <= hi[3 * j + d];
                corner[d] = std::max(lo[3 * j + d], ql[d]);
            }
            if (overlap) expected.emplace_back(cellOf(corner, L), -j);
        }
        std::sort(expected.begin(), expected.end());
        std::vector<int32_t> want, got;
        for (const auto& [cell, mj] : expected) want.push_back(-mj);
        g.forOverlapping(ql, qh, [&](int32_t j) { got.push_back(j); });
        ASSERT_EQ(got, want) << "query " << q;
    }
}

}  // namespace

TEST(CellGrid, DenseBlockVisitsCellsInOrderAndItemsDescending) { checkCellGrid(4.0); }
TEST(CellGrid, HashTableVisitsCellsInOrderAndItemsDescending) { checkCellGrid(1e6); }
TEST(BoxGrid, DenseBlockReportsEachOverlapOnceInOrder) { checkBoxGrid(4.0); }
TEST(BoxGrid, HashTableReportsEachOverlapOnceInOrder) { checkBoxGrid(1e6); }
