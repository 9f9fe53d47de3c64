#include "ThreadLayout.hpp"

#include <algorithm>
#include <limits>

namespace qdem {

void ThreadLayout::build(const int32_t* tetNodes, const std::vector<TetSegment>& ranges, int threads, long v,
                         int doublesPerNode) {
    stride = doublesPerNode;
    nThreads = std::max(1, threads);
    version = v;
    long total = 0;
    for (const TetSegment& r : ranges) total += r.t1 - r.t0;
    share.assign(nThreads, {});
    nodeLo.assign(nThreads, std::numeric_limits<int32_t>::max());
    nodeHi.assign(nThreads, -1);
    buffers.resize(nThreads);
    // Thread t takes positions [total*t/n, total*(t+1)/n) of the concatenated ranges.
    std::size_t r = 0;
    int32_t at = ranges.empty() ? 0 : ranges[0].t0;
    for (int t = 0; t < nThreads; ++t) {
        long want = total * (t + 1) / nThreads - total * t / nThreads;
        while (want > 0 && r < ranges.size()) {
            const int32_t take = static_cast<int32_t>(std::min<long>(want, ranges[r].t1 - at));
            if (take > 0) {
                share[t].push_back({ranges[r].piece, at, at + take});
                for (int32_t e = at; e < at + take; ++e)
                    for (int k = 0; k < 4; ++k) {
                        nodeLo[t] = std::min(nodeLo[t], tetNodes[4 * e + k]);
                        nodeHi[t] = std::max(nodeHi[t], tetNodes[4 * e + k]);
                    }
            }
            at += take;
            want -= take;
            if (at == ranges[r].t1 && ++r < ranges.size()) at = ranges[r].t0;
        }
        if (nodeHi[t] < nodeLo[t]) nodeLo[t] = 0, nodeHi[t] = -1;  // empty share
        buffers[t].assign(static_cast<std::size_t>(stride) * static_cast<std::size_t>(nodeHi[t] - nodeLo[t] + 1), 0.0);
    }
}

}  // namespace qdem
