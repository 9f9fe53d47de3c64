// The surfaces of all pieces in global ids, with the adjacency that contact
// detection needs: neighbour triangles across each edge, triangles around each
// surface node, and for each tetrahedron which of its faces are on the surface
// (to skip the interior ones, the seed's case C).
#pragma once
#include <cstdint>
#include <vector>

namespace qdem {

struct PieceInfo;

struct SurfaceIndex {
    // Triangles (outward), 3 global node ids each.
    std::vector<int32_t> tri, triPiece, triTet;
    std::vector<int32_t> triNbr;             // 3 per triangle: across edge k (corners k, k+1)
    // Triangles around each surface node: CSR indexed by surface-node index.
    std::vector<int32_t> nodeTriStart, nodeTris;
    std::vector<int32_t> surfIndexOfNode;    // per global node: index in surfNodes or -1
    // Edges, 2 global node ids each.
    std::vector<int32_t> edge, edgePiece;
    // Tets: surface tets (global ids) and, per global tet, the surface triangle
    // on each face (face k opposite corner k) or -1.
    std::vector<int32_t> surfTets, tetFaceTri;
    // Per piece: its triangles, edges and surface tets are contiguous ranges.
    std::vector<int32_t> pieceTriStart, pieceEdgeStart, pieceSurfTetStart;

    std::size_t nTris() const { return triPiece.size(); }
    std::size_t nEdges() const { return edgePiece.size(); }

    // Feature ("sharp") edges: the two faces meet at more than a set angle.
    // Edge-edge contact is sought between feature edges only: an edge inside
    // a flat or gently curved stretch of surface is no edge of the body, and
    // touches there are point-polygon contacts.
    std::vector<uint8_t> edgeSharp;
    double sharpAngle = -1;  // the angle edgeSharp was computed for

    void build(const std::vector<PieceInfo>& pieces, const int32_t* tetNodes, std::size_t nTets,
               const int32_t* surfNodes, std::size_t nSurf, std::size_t nNodes);
    // Classifies edges with the reference positions X (3 per node).
    void classifyEdges(const double* X, double angle);
};

}  // namespace qdem
