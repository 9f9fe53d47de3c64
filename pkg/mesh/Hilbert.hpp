// Space-filling-curve ordering: nodes and tets that are close in space end up
// close in memory, which is what keeps the element loop and the per-thread
// force buffers cache friendly (and what MPI partitioning will split along).
#pragma once
#include <cstdint>
#include <vector>

#include "TetMesh.hpp"

namespace qdem {

// Hilbert index (21 bits per axis) of a point in the box [lo, hi].
uint64_t hilbertKey(const double p[3], const double lo[3], const double hi[3]);

// Sorts tets by the Hilbert key of their centroid and renumbers nodes by
// first use in that order.  Returns, for each new node index, the old one;
// tetOldOf (when given) receives, for each new tet index, the old one.
std::vector<int32_t> hilbertReorder(TetMesh& m, std::vector<int32_t>* tetOldOf = nullptr);

}  // namespace qdem
