// A tetrahedral mesh as flat arrays: the input format of every piece.
#pragma once
#include <cstdint>
#include <vector>

namespace qdem {

struct TetMesh {
    std::vector<double> nodes;   // 3 * nNodes, x y z per node
    std::vector<int32_t> tets;   // 4 * nTets, node indices (0-based)

    std::size_t nNodes() const { return nodes.size() / 3; }
    std::size_t nTets() const { return tets.size() / 4; }
};

// Six times the signed volume of tetrahedron t (positive = right-handed).
double tetSixVolume(const TetMesh& m, std::size_t t);

// Throws InputError naming the first problem found: wrong array sizes, NaN or
// infinite coordinates, node indices out of range, repeated nodes in a tet,
// inverted tets (negative volume) and zero-volume tets (volume below
// relTol * mean-edge^3).  Unused nodes are allowed.
void checkMesh(const TetMesh& m, double relTol = 1e-10);

// Removes the flat tetrahedra (volume at most relTol * mean-edge^3, as
// checkMesh counts zero) that lie in the surface: two of their faces on the
// boundary (faces of no other tetrahedron), so all four corners are on it.
// Removing one exposes its two other faces, which cover the same flat patch:
// the shape and the surface are unchanged.  (CGAL Mesh_3 leaves such slivers
// on the flat faces of a plate thinner than its cells.)  Flat tetrahedra
// inside are left for checkMesh to name.  Returns the number removed.
std::size_t dropFlatSurfaceTets(TetMesh& m, double relTol = 1e-10);

// Flips every tetrahedron with negative volume (swaps its last two nodes).
// Returns the number flipped.  Use for files written with the opposite
// orientation convention, never to hide a mesh that is tangled.
std::size_t orientPositive(TetMesh& m);

}  // namespace qdem
