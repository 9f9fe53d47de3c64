// TEMPORARY lead's stand-in (replaced by the helper's implementation).
#include "Partition.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

#include "../mesh/Hilbert.hpp"

namespace qdem {

double Partition::imbalance() const {
    if (rankWeight.empty()) return 1;
    double mx = 0, sum = 0;
    for (double w : rankWeight) mx = std::max(mx, w), sum += w;
    return sum > 0 ? mx * rankWeight.size() / sum : 1;
}

std::size_t Halo::nGhosts() const {
    std::size_t n = 0;
    for (const auto& r : recv) n += r.size();
    return n;
}

Partition partitionHilbert(const PartitionInput& in, const PartitionOptions& opt) {
    Partition p;
    p.nRanks = std::max(1, opt.nRanks);
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d] = 1e300, hi[d] = -1e300;
    for (int32_t i = 0; i < in.nNodes; ++i)
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], in.pos[3 * i + d]), hi[d] = std::max(hi[d], in.pos[3 * i + d]);
    std::vector<uint64_t> key(in.nNodes);
    for (int32_t i = 0; i < in.nNodes; ++i) key[i] = hilbertKey(in.pos + 3 * i, lo, hi);
    std::vector<double> w(in.nNodes, 0.0);
    for (int32_t t = 0; t < in.nTets; ++t)
        for (int k = 0; k < 4; ++k) w[in.tetNodes[4 * t + k]] += 0.25;
    std::vector<int32_t> order(in.nNodes);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
    const double total = std::accumulate(w.begin(), w.end(), 0.0);
    p.nodeOwner.assign(in.nNodes, 0);
    double cum = 0;
    for (int32_t j = 0; j < in.nNodes; ++j) {
        const int32_t n = order[j];
        int r = total > 0 ? static_cast<int>((cum + 0.5 * w[n]) / total * p.nRanks) : 0;
        p.nodeOwner[n] = std::min(r, p.nRanks - 1);
        cum += w[n];
    }
    p.tetOwner.assign(in.nTets, 0);
    p.rankWeight.assign(p.nRanks, 0.0);
    for (int32_t t = 0; t < in.nTets; ++t) {
        int r = p.nRanks;
        for (int k = 0; k < 4; ++k) r = std::min(r, p.nodeOwner[in.tetNodes[4 * t + k]]);
        p.tetOwner[t] = r;
        p.rankWeight[r] += 1;
    }
    return p;
}

Halo elementHalo(const Partition& p, const PartitionInput& in, int rank) {
    Halo h;
    h.rank = rank;
    std::vector<std::vector<int32_t>> recv(p.nRanks), send(p.nRanks);
    for (int32_t n = 0; n < in.nNodes; ++n)
        if (p.nodeOwner[n] == rank) h.ownedNodes.push_back(n);
    for (int32_t t = 0; t < in.nTets; ++t) {
        const int o = p.tetOwner[t];
        if (o == rank) h.ownedTets.push_back(t);
        for (int k = 0; k < 4; ++k) {
            const int32_t n = in.tetNodes[4 * t + k];
            const int no = p.nodeOwner[n];
            if (o == rank && no != rank) recv[no].push_back(n);
            if (o != rank && no == rank) send[o].push_back(n);
        }
    }
    for (int r = 0; r < p.nRanks; ++r) {
        for (auto* v : {&recv[r], &send[r]}) {
            std::sort(v->begin(), v->end());
            v->erase(std::unique(v->begin(), v->end()), v->end());
        }
        if (!recv[r].empty() || !send[r].empty()) {
            h.neighbours.push_back(r);
            h.recv.push_back(recv[r]);
            h.send.push_back(send[r]);
        }
    }
    return h;
}

}  // namespace qdem
