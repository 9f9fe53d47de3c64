#include "SurfaceIndex.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

#include "../mesh/PieceInfo.hpp"

namespace qdem {

void SurfaceIndex::build(const std::vector<PieceInfo>& pieces, const int32_t* tetNodes, std::size_t nTets,
                         const int32_t* surfNodes, std::size_t nSurf, std::size_t nNodes) {
    tri.clear(), triPiece.clear(), triTet.clear(), edge.clear(), edgePiece.clear(), surfTets.clear();
    pieceTriStart.assign(1, 0), pieceEdgeStart.assign(1, 0), pieceSurfTetStart.assign(1, 0);
    for (std::size_t ip = 0; ip < pieces.size(); ++ip) {
        const Surface& s = pieces[ip].surface;
        pieceTriStart.push_back(pieceTriStart.back() + static_cast<int32_t>(s.nTriangles()));
        pieceEdgeStart.push_back(pieceEdgeStart.back() + static_cast<int32_t>(s.nEdges()));
        pieceSurfTetStart.push_back(pieceSurfTetStart.back() + static_cast<int32_t>(s.tets.size()));
        tri.insert(tri.end(), s.triangles.begin(), s.triangles.end());
        triTet.insert(triTet.end(), s.triTet.begin(), s.triTet.end());
        triPiece.insert(triPiece.end(), s.nTriangles(), static_cast<int32_t>(ip));
        edge.insert(edge.end(), s.edges.begin(), s.edges.end());
        edgePiece.insert(edgePiece.end(), s.nEdges(), static_cast<int32_t>(ip));
        surfTets.insert(surfTets.end(), s.tets.begin(), s.tets.end());
    }
    const auto nt = static_cast<int32_t>(nTris());

    surfIndexOfNode.assign(nNodes, -1);
    for (std::size_t i = 0; i < nSurf; ++i) surfIndexOfNode[surfNodes[i]] = static_cast<int32_t>(i);

    // Triangles around each surface node.
    nodeTriStart.assign(nSurf + 1, 0);
    for (int32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) ++nodeTriStart[surfIndexOfNode[tri[3 * t + k]] + 1];
    for (std::size_t i = 0; i < nSurf; ++i) nodeTriStart[i + 1] += nodeTriStart[i];
    nodeTris.assign(nodeTriStart.back(), -1);
    std::vector<int32_t> fill(nodeTriStart.begin(), nodeTriStart.end() - 1);
    for (int32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) nodeTris[fill[surfIndexOfNode[tri[3 * t + k]]]++] = t;

    // Neighbour across each edge: the other triangle holding the same pair.
    triNbr.assign(3 * nTris(), -1);
    for (int32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const int32_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
            const int32_t sa = surfIndexOfNode[a];
            for (int32_t q = nodeTriStart[sa]; q < nodeTriStart[sa + 1]; ++q) {
                const int32_t u = nodeTris[q];
                if (u == t) continue;
                const int32_t* c = &tri[3 * u];
                if ((c[0] == b || c[1] == b || c[2] == b)) triNbr[3 * t + k] = u;
            }
        }

    // Surface faces of each tet (face k is opposite corner k).
    tetFaceTri.assign(4 * nTets, -1);
    for (int32_t t = 0; t < nt; ++t) {
        const int32_t e = triTet[t];
        for (int k = 0; k < 4; ++k) {
            const int32_t opposite = tetNodes[4 * e + k];
            if (opposite != tri[3 * t] && opposite != tri[3 * t + 1] && opposite != tri[3 * t + 2])
                tetFaceTri[4 * e + k] = t;
        }
    }
}

void SurfaceIndex::classifyEdges(const double* X, double angle) {
    edgeSharp.assign(nEdges(), 0);
    const double cosLimit = std::cos(angle);
    auto normal = [&](int32_t t) {
        const Eigen::Map<const Eigen::Vector3d> a(X + 3 * tri[3 * t]), b(X + 3 * tri[3 * t + 1]), c(X + 3 * tri[3 * t + 2]);
        return Eigen::Vector3d((b - a).cross(c - a).normalized());
    };
    for (std::size_t t = 0; t < nTris(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int32_t nb = triNbr[3 * t + k];
            if (nb < static_cast<int32_t>(t)) continue;  // each edge once, from its lower triangle
            int32_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
            if (a > b) std::swap(a, b);
            // Edges of a piece are sorted (a, b) pairs within its range.
            const int32_t p = triPiece[t];
            int32_t lo = pieceEdgeStart[p], hi = pieceEdgeStart[p + 1];
            while (lo < hi) {
                const int32_t mid = (lo + hi) / 2;
                if (edge[2 * mid] < a || (edge[2 * mid] == a && edge[2 * mid + 1] < b)) lo = mid + 1;
                else hi = mid;
            }
            if (lo < pieceEdgeStart[p + 1] && edge[2 * lo] == a && edge[2 * lo + 1] == b)
                edgeSharp[lo] = normal(static_cast<int32_t>(t)).dot(normal(nb)) < cosLimit;
        }
    sharpAngle = angle;
}

}  // namespace qdem
