// Halos of a partition (Partition.hpp): who reads whose nodes.
//
// Every read is one (reader, owner, node) triple; a rank's recv lists are its
// triples as reader, its send lists the triples where it is the owner.  Both
// come from the same set of triples, so send[r][s] == recv[s][r] holds by
// construction, whichever ranks are asked for.
#include <algorithm>
#include <cmath>

#include "../contact/CellGrid.hpp"
#include "Partition.hpp"

namespace qdem {

namespace {

struct Read {
    int32_t reader, owner, node;
};

int32_t pieceOfNode(const PartitionInput& in, int32_t n) {
    if (in.nPieces <= 0 || n < in.pieceNodeBegin[0] || n >= in.pieceNodeBegin[in.nPieces]) return -1;
    const int32_t* b = in.pieceNodeBegin;
    return static_cast<int32_t>(std::upper_bound(b, b + in.nPieces + 1, n) - b) - 1;
}

// Pairs of surface nodes of different owners and different pieces within
// `reach`: each makes both owners read the other's node.  Only pairs with an
// owner among the asked ranks are kept (asked[r] >= 0).  A cell grid of side
// `reach` over the surface nodes: each node looks at the <= 27 cells around
// it, so the cost is O(nSurf) times the nodes per cell.
void contactReads(const Partition& p, const PartitionInput& in, const int32_t* surf, int32_t nSurf, double reach,
                  const std::vector<int>& asked, std::vector<Read>& reads) {
    std::vector<double> pts(3 * static_cast<std::size_t>(nSurf));
    std::vector<int32_t> piece(nSurf);
    for (int32_t i = 0; i < nSurf; ++i) {
        for (int d = 0; d < 3; ++d) pts[3 * i + d] = in.pos[3 * surf[i] + d];
        piece[i] = pieceOfNode(in, surf[i]);
    }
    CellGrid grid;
    grid.build(pts.data(), nSurf, reach);
    const double reach2 = reach * reach;
    const int32_t* owner = p.nodeOwner.data();
    for (int32_t i = 0; i < nSurf; ++i) {
        const int32_t a = surf[i], oa = owner[a];
        // A pair with one asked owner is found from that owner's node.
        if (asked[oa] < 0) continue;
        const double* x = pts.data() + 3 * i;
        const double lo[3] = {x[0] - reach, x[1] - reach, x[2] - reach};
        const double hi[3] = {x[0] + reach, x[1] + reach, x[2] + reach};
        grid.forRange(lo, hi, [&](int32_t j) {
            const int32_t b = surf[j], ob = owner[b];
            // Contacts are between pieces (PieceContactPhase): nodes of one
            // piece never need each other for contact.
            if (ob == oa || (piece[i] >= 0 && piece[i] == piece[j])) return;
            const double* y = pts.data() + 3 * j;
            const double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
            if (dx * dx + dy * dy + dz * dz > reach2) return;
            reads.push_back({oa, ob, b});
            reads.push_back({ob, oa, a});
        });
    }
}

}  // namespace

std::size_t Halo::nGhosts() const {
    std::size_t n = 0;
    for (const auto& l : recv) n += l.size();
    return n;
}

std::vector<Halo> haloOf(const Partition& p, const PartitionInput& in, const int32_t* surfNodes, int32_t nSurf,
                         double contactReach, const std::vector<int>& ranks) {
    const int P = p.nRanks;
    std::vector<int> asked(P, -1);  // rank -> index in the answer
    std::vector<Halo> halos(ranks.size());
    for (std::size_t i = 0; i < ranks.size(); ++i) {
        asked[ranks[i]] = static_cast<int>(i);
        halos[i].rank = ranks[i];
    }
    for (int32_t n = 0; n < in.nNodes; ++n)
        if (asked[p.nodeOwner[n]] >= 0) halos[asked[p.nodeOwner[n]]].ownedNodes.push_back(n);
    for (int32_t t = 0; t < in.nTets; ++t)
        if (asked[p.tetOwner[t]] >= 0) halos[asked[p.tetOwner[t]]].ownedTets.push_back(t);

    // Element reads: the owner of a tet reads its nodes owned elsewhere.
    std::vector<Read> reads;
    for (int32_t t = 0; t < in.nTets; ++t) {
        const int32_t r = p.tetOwner[t];
        for (int k = 0; k < 4; ++k) {
            const int32_t n = in.tetNodes[4 * t + k], o = p.nodeOwner[n];
            if (o != r && (asked[r] >= 0 || asked[o] >= 0)) reads.push_back({r, o, n});
        }
    }
    if (contactReach > 0 && nSurf > 0) contactReads(p, in, surfNodes, nSurf, contactReach, asked, reads);

    auto byReader = [](const Read& a, const Read& b) {
        return a.reader != b.reader ? a.reader < b.reader : a.owner != b.owner ? a.owner < b.owner : a.node < b.node;
    };
    auto same = [](const Read& a, const Read& b) { return a.reader == b.reader && a.node == b.node; };
    std::sort(reads.begin(), reads.end(), byReader);
    reads.erase(std::unique(reads.begin(), reads.end(), same), reads.end());

    // Per asked rank: (neighbour, list) in neighbour order, recv then send.
    struct Side {
        std::vector<int> nbr;
        std::vector<std::vector<int32_t>> list;
    };
    std::vector<Side> recv(ranks.size()), send(ranks.size());
    auto collect = [&](std::vector<Side>& sides, auto self, auto other) {
        for (const Read& rd : reads) {
            const int h = asked[self(rd)];
            if (h < 0) continue;
            Side& s = sides[h];
            if (s.nbr.empty() || s.nbr.back() != other(rd)) {
                s.nbr.push_back(other(rd));
                s.list.emplace_back();
            }
            s.list.back().push_back(rd.node);
        }
    };
    collect(recv, [](const Read& r) { return r.reader; }, [](const Read& r) { return r.owner; });
    std::sort(reads.begin(), reads.end(), [](const Read& a, const Read& b) {
        return a.owner != b.owner ? a.owner < b.owner : a.reader != b.reader ? a.reader < b.reader : a.node < b.node;
    });
    collect(send, [](const Read& r) { return r.owner; }, [](const Read& r) { return r.reader; });

    // Merge both sides onto one ascending neighbour list (a neighbour may
    // only send or only receive: an empty list on the other side).
    for (std::size_t h = 0; h < ranks.size(); ++h) {
        Halo& halo = halos[h];
        std::size_t i = 0, j = 0;
        const Side &rv = recv[h], &sd = send[h];
        while (i < rv.nbr.size() || j < sd.nbr.size()) {
            const int a = i < rv.nbr.size() ? rv.nbr[i] : P, b = j < sd.nbr.size() ? sd.nbr[j] : P;
            const int nb = std::min(a, b);
            halo.neighbours.push_back(nb);
            halo.recv.emplace_back(a == nb ? std::move(recv[h].list[i++]) : std::vector<int32_t>());
            halo.send.emplace_back(b == nb ? std::move(send[h].list[j++]) : std::vector<int32_t>());
        }
    }
    return halos;
}

Halo elementHalo(const Partition& p, const PartitionInput& in, int rank) {
    return std::move(haloOf(p, in, nullptr, 0, 0.0, {rank}).front());
}

std::vector<Halo> haloAll(const Partition& p, const PartitionInput& in, const int32_t* surfNodes, int32_t nSurf,
                          double contactReach) {
    std::vector<int> all(p.nRanks);
    for (int r = 0; r < p.nRanks; ++r) all[r] = r;
    return haloOf(p, in, surfNodes, nSurf, contactReach, all);
}

}  // namespace qdem
