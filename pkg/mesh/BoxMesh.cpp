#include "BoxMesh.hpp"

#include <algorithm>
#include <array>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

namespace {

struct Grid {
    int nx, ny, nz;
    int32_t id(int i, int j, int k) const { return static_cast<int32_t>((k * (ny + 1) + j) * (nx + 1) + i); }
};

void pushTet(TetMesh& m, int32_t a, int32_t b, int32_t c, int32_t d) {
    m.tets.insert(m.tets.end(), {a, b, c, d});
}

// Kuhn (Freudenthal) split: six tets around the diagonal from corner 000 to 111.
void kuhnCell(TetMesh& m, const Grid& g, int i, int j, int k) {
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& p : perms) {
        int c[3] = {0, 0, 0};
        int32_t v[4];
        v[0] = g.id(i, j, k);
        for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            v[s + 1] = g.id(i + c[0], j + c[1], k + c[2]);
        }
        pushTet(m, v[0], v[1], v[2], v[3]);
    }
}

// Five tets: four corner tets and a central one; the cut alternates with the
// parity of the cell so that neighbouring cells share face diagonals.
void fiveCell(TetMesh& m, const Grid& g, int i, int j, int k) {
    auto v = [&](int a, int b, int c) { return g.id(i + a, j + b, k + c); };
    if ((i + j + k) % 2 == 0) {
        pushTet(m, v(1, 0, 0), v(0, 1, 0), v(0, 0, 1), v(1, 1, 1));
        pushTet(m, v(0, 0, 0), v(1, 0, 0), v(0, 1, 0), v(0, 0, 1));
        pushTet(m, v(1, 1, 0), v(1, 0, 0), v(0, 1, 0), v(1, 1, 1));
        pushTet(m, v(1, 0, 1), v(1, 0, 0), v(0, 0, 1), v(1, 1, 1));
        pushTet(m, v(0, 1, 1), v(0, 1, 0), v(0, 0, 1), v(1, 1, 1));
    } else {
        pushTet(m, v(0, 0, 0), v(1, 1, 0), v(1, 0, 1), v(0, 1, 1));
        pushTet(m, v(1, 0, 0), v(0, 0, 0), v(1, 1, 0), v(1, 0, 1));
        pushTet(m, v(0, 1, 0), v(0, 0, 0), v(1, 1, 0), v(0, 1, 1));
        pushTet(m, v(0, 0, 1), v(0, 0, 0), v(1, 0, 1), v(0, 1, 1));
        pushTet(m, v(1, 1, 1), v(1, 1, 0), v(1, 0, 1), v(0, 1, 1));
    }
}

// Twelve tets: each cell face split into two triangles along the diagonal
// through its smallest global node id (so both cells sharing a face agree),
// each triangle coned to the cell's centre node.
void twelveCell(TetMesh& m, const Grid& g, int i, int j, int k, int32_t centre) {
    auto v = [&](int a, int b, int c) { return g.id(i + a, j + b, k + c); };
    const std::array<std::array<int32_t, 4>, 6> faces = {{
        {v(0, 0, 0), v(0, 1, 0), v(0, 1, 1), v(0, 0, 1)},
        {v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)},
        {v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)},
        {v(0, 1, 0), v(1, 1, 0), v(1, 1, 1), v(0, 1, 1)},
        {v(0, 0, 0), v(1, 0, 0), v(1, 1, 0), v(0, 1, 0)},
        {v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)},
    }};
    for (auto q : faces) {
        const int r = static_cast<int>(std::min_element(q.begin(), q.end()) - q.begin());
        std::rotate(q.begin(), q.begin() + r, q.end());
        pushTet(m, q[0], q[1], q[2], centre);
        pushTet(m, q[0], q[2], q[3], centre);
    }
}

}  // namespace

TetMesh boxMesh(int nx, int ny, int nz, double lx, double ly, double lz, int tetsPerCell) {
    if (nx < 1 || ny < 1 || nz < 1)
        throw InputError(cat("boxMesh: cell counts must be >= 1, got ", nx, "x", ny, "x", nz));
    if (!(lx > 0 && ly > 0 && lz > 0))
        throw InputError(cat("boxMesh: sizes must be > 0, got ", lx, "x", ly, "x", lz));
    if (tetsPerCell != 5 && tetsPerCell != 6 && tetsPerCell != 12)
        throw InputError(cat("boxMesh: tetsPerCell must be 5, 6 or 12, got ", tetsPerCell));
    const Grid g{nx, ny, nz};
    TetMesh m;
    const std::size_t nGrid = static_cast<std::size_t>(nx + 1) * (ny + 1) * (nz + 1);
    const std::size_t nCells = static_cast<std::size_t>(nx) * ny * nz;
    m.nodes.reserve(3 * (nGrid + (tetsPerCell == 12 ? nCells : 0)));
    for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j)
            for (int i = 0; i <= nx; ++i)
                m.nodes.insert(m.nodes.end(), {lx * (double(i) / nx - 0.5), ly * (double(j) / ny - 0.5),
                                               lz * (double(k) / nz - 0.5)});
    m.tets.reserve(4 * nCells * tetsPerCell);
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                if (tetsPerCell == 6) {
                    kuhnCell(m, g, i, j, k);
                } else if (tetsPerCell == 5) {
                    fiveCell(m, g, i, j, k);
                } else {
                    const auto centre = static_cast<int32_t>(m.nodes.size() / 3);
                    m.nodes.insert(m.nodes.end(), {lx * ((i + 0.5) / nx - 0.5), ly * ((j + 0.5) / ny - 0.5),
                                                   lz * ((k + 0.5) / nz - 0.5)});
                    twelveCell(m, g, i, j, k, centre);
                }
            }
    orientPositive(m);
    return m;
}

}  // namespace qdem
