// How the element loop is shared among threads without atomics.
//
// The tets to compute (every piece's, or only the awake pieces' when some
// sleep: doc/sleeping.md) are split into equal contiguous shares, one per
// thread; a share is a list of segments, each inside one piece.  A thread
// adds its nodal forces into a private buffer covering only the node range its
// share touches; thanks to the space-filling-curve order those ranges barely
// overlap, so the buffers together are about one force array in size and the
// integrator sums the (at most a few) buffers covering each node.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Aligned.hpp"

namespace qdem {

struct TetSegment {
    int32_t piece, t0, t1;  // tets [t0, t1) of one piece
};

struct ThreadLayout {
    int nThreads = 0;
    long version = -1;                           // the World's awake-set version it was built for
    std::vector<std::vector<TetSegment>> share;  // per thread
    std::vector<int32_t> nodeLo, nodeHi;         // node range [lo, hi] touched by each share
    // Per thread: `stride` doubles per node from nodeLo on (3, or 4 with a
    // zero pad so that the element kernel adds a node's force with one
    // aligned vector operation: NodeGather.hpp).
    std::vector<AlignedVector<double>> buffers;
    int stride = 3;

    bool matches(int threads, long v) const { return threads == nThreads && v == version; }
    // Node n's sum over the buffers that cover it (3 values into s).
    void sumNode(int32_t n, double* s) const {
        s[0] = s[1] = s[2] = 0;
        for (int t = 0; t < nThreads; ++t)
            if (n >= nodeLo[t] && n <= nodeHi[t]) {
                const double* b = buffers[t].data() + stride * (n - nodeLo[t]);
                s[0] += b[0], s[1] += b[1], s[2] += b[2];
            }
    }
    // ranges: the segments to compute, in tet order (one per piece);
    // doublesPerNode: the buffers' stride.
    void build(const int32_t* tetNodes, const std::vector<TetSegment>& ranges, int threads, long v,
               int doublesPerNode = 3);
};

}  // namespace qdem
