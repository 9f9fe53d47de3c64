#include "BoxMesh.hpp"

#include <array>
#include <cmath>

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

// Whether cell i of n lies in the lower half of its axis (the middle cell of
// an odd count does not: it cannot be mirror-symmetric with any of these
// splits, and keeps the upper half's orientation).
bool lowerHalf(int i, int n) { return 2 * i + 1 < n; }

// Kuhn (Freudenthal) split: six tets around one main diagonal of the cell.
// The diagonal runs from the cell corner nearest the box centre to the
// farthest one: cells in the lower half of an axis use the split mirrored
// about the cell's mid-plane of that axis, so the mesh is the mirror image
// of itself about the box's three mid-planes.  Conforming: the diagonal a
// cell puts on its faces normal to x depends only on its y and z flips, which
// the neighbour along x shares (likewise for y and z).
void kuhnCell(TetMesh& m, const Grid& g, int i, int j, int k) {
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    const int flip[3] = {lowerHalf(i, g.nx), lowerHalf(j, g.ny), lowerHalf(k, g.nz)};
    auto node = [&](const int c[3]) {
        return g.id(i + (flip[0] ? 1 - c[0] : c[0]), j + (flip[1] ? 1 - c[1] : c[1]), k + (flip[2] ? 1 - c[2] : c[2]));
    };
    for (const auto& p : perms) {
        int c[3] = {0, 0, 0};
        int32_t v[4];
        v[0] = node(c);
        for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            v[s + 1] = node(c);
        }
        pushTet(m, v[0], v[1], v[2], v[3]);
    }
}

// Five tets: four corner tets and a central one; the cut alternates with the
// parity of the cell so that neighbouring cells share face diagonals (the
// only conforming 5-tet pattern, up to the choice of parity).  A mirror about
// an axis's mid-plane maps cell i to n-1-i and turns one cut into the other:
// the pattern is mirror-symmetric about that plane exactly when n is even,
// whatever the parity anchor (with odd counts the whole mesh, not just the
// middle layer, differs from its mirror image; with equal odd counts nx = ny
// it is still symmetric under the half-turn about z, which keeps the mass
// centre of each face at the face's centre).
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

// Twelve tets: each cell face split into two triangles, each coned to the
// cell's centre node.  A face's diagonal is chosen from where the face's
// centre lies relative to the box centre: in the face's two in-plane axes
// (a, b) with signed offsets (da, db) of the face centre, the diagonal along
// (1, 1) when da*db > 0, along (1, -1) when da*db < 0: it points towards the
// box's centre line, and a mirror about a mid-plane maps it onto the diagonal
// the mirrored face chooses.  Both cells sharing a face compute the same
// offsets, so the mesh is conforming.  A face whose centre lies on a
// mid-plane (da or db = 0: the middle column of an odd count) has no
// symmetric diagonal; it takes (1, 1).
void twelveCell(TetMesh& m, const Grid& g, int i, int j, int k, int32_t centre) {
    const int n[3] = {g.nx, g.ny, g.nz};
    const int cell[3] = {i, j, k};
    for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        // Signed offsets of the face centre, in half cells (integers: exact ties).
        const int da = 2 * cell[a] + 1 - n[a], db = 2 * cell[b] + 1 - n[b];
        const bool mainDiagonal = static_cast<long>(da) * db >= 0;
        for (int side = 0; side < 2; ++side) {
            auto v = [&](int ua, int ub) {
                int c[3];
                c[axis] = cell[axis] + side;
                c[a] = cell[a] + ua;
                c[b] = cell[b] + ub;
                return g.id(c[0], c[1], c[2]);
            };
            if (mainDiagonal) {
                pushTet(m, v(0, 0), v(1, 0), v(1, 1), centre);
                pushTet(m, v(0, 0), v(1, 1), v(0, 1), centre);
            } else {
                pushTet(m, v(1, 0), v(1, 1), v(0, 1), centre);
                pushTet(m, v(1, 0), v(0, 1), v(0, 0), centre);
            }
        }
    }
}

}  // namespace
TetMesh boxMesh(int nx, int ny, int nz, double lx, double ly, double lz, int tetsPerCell) {
    if (nx < 1 || ny < 1 || nz < 1)
        throw InputError(cat("boxMesh: cell counts must be >= 1, got ", nx, "x", ny, "x", nz));
    if (!(lx > 0 && ly > 0 && lz > 0) || !std::isfinite(lx) || !std::isfinite(ly) || !std::isfinite(lz))
        throw InputError(cat("boxMesh: sizes must be finite and > 0, got ", lx, "x", ly, "x", lz));
    if (tetsPerCell != 5 && tetsPerCell != 6 && tetsPerCell != 12)
        throw InputError(cat("boxMesh: tetsPerCell must be 5, 6 or 12, got ", tetsPerCell));
    {  // node ids are int32 (and Grid::id computes in int)
        const double cells = double(nx) * ny * nz;
        const double nodes = double(nx + 1.0) * (ny + 1.0) * (nz + 1.0) + (tetsPerCell == 12 ? cells : 0.0);
        if (nodes > 2147483646.0 || cells * tetsPerCell > 2147483646.0)
            throw InputError(cat("boxMesh: ", nx, "x", ny, "x", nz, " cells give ", nodes, " nodes and ",
                                 cells * tetsPerCell, " tetrahedra, beyond 32-bit indices; use fewer cells"));
    }
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
