#include "Surface.hpp"

#include <algorithm>
#include <array>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

namespace {

// Outward faces of a positively oriented tet (a0 a1 a2 a3): the face opposite
// node k, wound so that its right-hand normal points away from node k.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
    std::array<int32_t, 3> sorted;
    int32_t tet;
    int8_t local;
    bool operator<(const FaceKey& o) const { return sorted < o.sorted; }
};

}  // namespace

Surface extractSurface(const TetMesh& m) {
    const std::size_t nt = m.nTets();
    std::vector<FaceKey> faces;
    faces.reserve(4 * nt);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 4; ++k) {
            FaceKey f;
            for (int i = 0; i < 3; ++i) f.sorted[i] = m.tets[4 * t + kFace[k][i]];
            std::sort(f.sorted.begin(), f.sorted.end());
            f.tet = static_cast<int32_t>(t);
            f.local = static_cast<int8_t>(k);
            faces.push_back(f);
        }
    std::sort(faces.begin(), faces.end());

    Surface s;
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
        if (j - i > 2)
            throw InputError(cat("mesh: non-manifold: face (", faces[i].sorted[0], ",", faces[i].sorted[1],
                                 ",", faces[i].sorted[2], ") is shared by ", j - i, " tetrahedra"));
        if (j - i == 1) {
            const FaceKey& f = faces[i];
            for (int q = 0; q < 3; ++q) s.triangles.push_back(m.tets[4 * f.tet + kFace[f.local][q]]);
            s.triTet.push_back(f.tet);
        }
        i = j;
    }

    // Boundary edges: each must be shared by exactly two boundary faces.
    // (first, second: the sorted end nodes; third: the face.)
    struct EdgeFace {
        int32_t first, second, face;
        bool operator<(const EdgeFace& o) const {
            return first != o.first ? first < o.first : second != o.second ? second < o.second : face < o.face;
        }
        bool same(const EdgeFace& o) const { return first == o.first && second == o.second; }
    };
    std::vector<EdgeFace> e;
    e.reserve(s.triangles.size());
    for (std::size_t f = 0; f < s.nTriangles(); ++f)
        for (int q = 0; q < 3; ++q) {
            int32_t a = s.triangles[3 * f + q], b = s.triangles[3 * f + (q + 1) % 3];
            e.push_back({std::min(a, b), std::max(a, b), static_cast<int32_t>(f)});
        }
    std::sort(e.begin(), e.end());
    // Corners (face, local vertex) joined across shared edges: at a manifold
    // vertex the faces around it form one fan, hence one group of corners.
    std::vector<int32_t> up(s.triangles.size());
    for (std::size_t c = 0; c < up.size(); ++c) up[c] = static_cast<int32_t>(c);
    auto root = [&](int32_t c) {
        while (up[c] != c) c = up[c] = up[up[c]];
        return c;
    };
    auto corner = [&](int32_t f, int32_t v) {
        int q = 0;
        while (s.triangles[3 * f + q] != v) ++q;
        return 3 * f + q;
    };
    for (std::size_t i = 0; i < e.size();) {
        std::size_t j = i + 1;
        while (j < e.size() && e[j].same(e[i])) ++j;
        if (j - i != 2)
            throw InputError(cat("mesh: non-manifold surface: edge (", e[i].first, ",", e[i].second,
                                 ") is shared by ", j - i, " boundary faces (expected 2)"));
        s.edges.push_back(e[i].first);
        s.edges.push_back(e[i].second);
        for (int32_t v : {e[i].first, e[i].second}) up[root(corner(e[i].face, v))] = root(corner(e[i + 1].face, v));
        i = j;
    }
    {
        std::vector<std::pair<int32_t, int32_t>> vc;  // (node, group of one of its corners)
        vc.reserve(up.size());
        for (std::size_t c = 0; c < up.size(); ++c) vc.emplace_back(s.triangles[c], root(static_cast<int32_t>(c)));
        std::sort(vc.begin(), vc.end());
        vc.erase(std::unique(vc.begin(), vc.end()), vc.end());
        for (std::size_t i = 1; i < vc.size(); ++i)
            if (vc[i].first == vc[i - 1].first)
                throw InputError(cat("mesh: non-manifold surface: node ", vc[i].first,
                                     " joins separate sheets of the boundary (the tetrahedra around it meet "
                                     "only at that node or along a pinched edge)"));
    }

    s.nodes.assign(s.triangles.begin(), s.triangles.end());
    std::sort(s.nodes.begin(), s.nodes.end());
    s.nodes.erase(std::unique(s.nodes.begin(), s.nodes.end()), s.nodes.end());
    s.tets = s.triTet;
    std::sort(s.tets.begin(), s.tets.end());
    s.tets.erase(std::unique(s.tets.begin(), s.tets.end()), s.tets.end());
    return s;
}

}  // namespace qdem
