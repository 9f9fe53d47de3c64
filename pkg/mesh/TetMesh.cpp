#include "TetMesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

double tetSixVolume(const TetMesh& m, std::size_t t) {
    const double* X = m.nodes.data();
    const int32_t* c = &m.tets[4 * t];
    const double* a = X + 3 * c[0];
    double e[3][3];
    for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) e[k][d] = X[3 * c[k + 1] + d] - a[d];
    return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
           e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
           e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

static double meanEdgeLength(const TetMesh& m) {
    const std::size_t nt = m.nTets();
    double sum = 0;
    for (std::size_t t = 0; t < nt; ++t) {
        const int32_t* c = &m.tets[4 * t];
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                double s = 0;
                for (int d = 0; d < 3; ++d) {
                    double x = m.nodes[3 * c[i] + d] - m.nodes[3 * c[j] + d];
                    s += x * x;
                }
                sum += std::sqrt(s);
            }
    }
    return nt ? sum / (6.0 * nt) : 0.0;
}

std::size_t dropFlatSurfaceTets(TetMesh& m, double relTol) {
    const double h = meanEdgeLength(m);
    const double minSix = 6.0 * relTol * h * h * h;
    std::size_t removed = 0;
    // (A removal can expose a flat neighbour's faces: passes until none.)
    for (bool again = true; again;) {
        again = false;
        const std::size_t nt = m.nTets();
        std::vector<std::size_t> flat;
        for (std::size_t t = 0; t < nt; ++t)
            if (std::fabs(tetSixVolume(m, t)) <= minSix) flat.push_back(t);
        if (flat.empty()) break;
        std::map<std::array<int32_t, 3>, int> faceCount;
        auto face = [&](std::size_t t, int k) {
            std::array<int32_t, 3> f{};
            int n = 0;
            for (int i = 0; i < 4; ++i)
                if (i != k) f[n++] = m.tets[4 * t + i];
            std::sort(f.begin(), f.end());
            return f;
        };
        for (std::size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 4; ++k) ++faceCount[face(t, k)];
        std::vector<char> drop(nt, 0);
        for (std::size_t t : flat) {
            int onSurface = 0;
            for (int k = 0; k < 4; ++k) onSurface += faceCount[face(t, k)] == 1;
            if (onSurface == 2) drop[t] = 1;
        }
        std::size_t out = 0;
        for (std::size_t t = 0; t < nt; ++t) {
            if (drop[t]) {
                ++removed;
                again = true;
                continue;
            }
            for (int i = 0; i < 4; ++i) m.tets[4 * out + i] = m.tets[4 * t + i];
            ++out;
        }
        m.tets.resize(4 * out);
    }
    return removed;
}

void checkMesh(const TetMesh& m, double relTol) {
    if (m.nodes.size() % 3 != 0)
        throw InputError(cat("mesh: node array length ", m.nodes.size(), " is not a multiple of 3"));
    if (m.tets.size() % 4 != 0)
        throw InputError(cat("mesh: tet array length ", m.tets.size(), " is not a multiple of 4"));
    const std::size_t nn = m.nNodes(), nt = m.nTets();
    if (nt == 0) throw InputError("mesh: no tetrahedra");
    for (std::size_t i = 0; i < m.nodes.size(); ++i)
        if (!std::isfinite(m.nodes[i]))
            throw InputError(cat("mesh: node ", i / 3, " has a NaN or infinite coordinate"));
    for (std::size_t t = 0; t < nt; ++t) {
        const int32_t* c = &m.tets[4 * t];
        for (int i = 0; i < 4; ++i) {
            if (c[i] < 0 || static_cast<std::size_t>(c[i]) >= nn)
                throw InputError(cat("mesh: tetrahedron ", t, " refers to node ", c[i],
                                     " but the mesh has ", nn, " nodes"));
            for (int j = 0; j < i; ++j)
                if (c[i] == c[j])
                    throw InputError(cat("mesh: tetrahedron ", t, " repeats node ", c[i],
                                         " (zero-volume tetrahedron)"));
        }
    }
    const double h = meanEdgeLength(m);
    const double minSix = 6.0 * relTol * h * h * h;
    for (std::size_t t = 0; t < nt; ++t) {
        const double v6 = tetSixVolume(m, t);
        if (std::fabs(v6) <= minSix)
            throw InputError(cat("mesh: tetrahedron ", t, " has zero volume (", v6 / 6.0,
                                 "; mean edge ", h, ")"));
        if (v6 < 0)
            throw InputError(cat("mesh: tetrahedron ", t, " is inverted (volume ", v6 / 6.0,
                                 " < 0); reorder its nodes or load with fixOrientation=True"));
    }
}

std::size_t orientPositive(TetMesh& m) {
    std::size_t flipped = 0;
    for (std::size_t t = 0; t < m.nTets(); ++t)
        if (tetSixVolume(m, t) < 0) {
            std::swap(m.tets[4 * t + 2], m.tets[4 * t + 3]);
            ++flipped;
        }
    return flipped;
}

}  // namespace qdem
