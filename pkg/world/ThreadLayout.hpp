// How the element loop is shared among threads without atomics.
//
// Tets are split into contiguous chunks, one per thread.  A thread adds its
// nodal forces into a private buffer covering only the node range its chunk
// touches; thanks to the space-filling-curve order those ranges barely
// overlap, so the buffers together are about one force array in size and the
// integrator sums the (at most a few) buffers covering each node.
#pragma once
#include <cstdint>
#include <vector>

namespace qdem {

struct ThreadLayout {
    int nThreads = 0;
    std::size_t nTets = 0;
    std::vector<int32_t> tetBegin;       // nThreads + 1 chunk bounds
    std::vector<int32_t> nodeLo, nodeHi; // node range [lo, hi] touched by each chunk
    std::vector<std::vector<double>> buffers;

    bool matches(int threads, std::size_t tets) const { return threads == nThreads && tets == nTets; }
    void build(const int32_t* tetNodes, std::size_t tets, int threads);
};

}  // namespace qdem
