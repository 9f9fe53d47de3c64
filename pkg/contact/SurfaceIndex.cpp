#include "SurfaceIndex.hpp"

#include <algorithm>
#include <map>

#include "../world/World.hpp"

namespace qdem {

void SurfaceIndex::build(const std::vector<PieceInfo>& pieces, const int32_t* tetNodes, std::size_t nTets,
                         const int32_t* surfNodes, std::size_t nSurf, std::size_t nNodes) {
    tri.clear(), triPiece.clear(), triTet.clear(), edge.clear(), edgePiece.clear(), surfTets.clear();
    for (std::size_t ip = 0; ip < pieces.size(); ++ip) {
        const Surface& s = pieces[ip].surface;
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

}  // namespace qdem
