// The weighted split along a space-filling key (Partition.hpp).
//
// Both partitioners share one engine: a key per node (Hilbert index, or the
// coordinate along the longest axis), whole small pieces keyed at their
// centroid, nodes sorted by (key, id), and cuts of equal cumulative weight.
#include "Partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "../mesh/Hilbert.hpp"

namespace qdem {

namespace {

struct Keyed {
    uint64_t key;
    int32_t node;
    bool operator<(const Keyed& o) const { return key != o.key ? key < o.key : node < o.node; }
};

struct Box {
    double lo[3], hi[3];
};

Box boundingBox(const PartitionInput& in) {
    Box b;
    for (int d = 0; d < 3; ++d) {
        b.lo[d] = std::numeric_limits<double>::max();
        b.hi[d] = std::numeric_limits<double>::lowest();
    }
    for (int32_t i = 0; i < in.nNodes; ++i)
        for (int d = 0; d < 3; ++d) {
            b.lo[d] = std::min(b.lo[d], in.pos[3 * i + d]);
            b.hi[d] = std::max(b.hi[d], in.pos[3 * i + d]);
        }
    if (in.nNodes == 0)
        for (int d = 0; d < 3; ++d) b.lo[d] = b.hi[d] = 0;
    return b;
}

// The Hilbert key of a point in the cube around the box: a cube, not the box
// itself, because hilbertKey scales each axis to its own span and a long
// thin box would give cells (and so rank domains) stretched along it.  A flat
// or point-like box gives a zero span on some axes: hilbertKey maps them to 0.
struct HilbertKeyer {
    double lo[3], hi[3];
    explicit HilbertKeyer(const Box& b) {
        double side = 0;
        for (int d = 0; d < 3; ++d) side = std::max(side, b.hi[d] - b.lo[d]);
        for (int d = 0; d < 3; ++d) {
            const double mid = 0.5 * (b.lo[d] + b.hi[d]);
            lo[d] = side > 0 ? mid - 0.5 * side : b.lo[d];
            hi[d] = side > 0 ? mid + 0.5 * side : b.lo[d];
        }
    }
    uint64_t operator()(const double p[3]) const { return hilbertKey(p, lo, hi); }
};

// The coordinate along the box's longest axis, as a 62-bit integer.
struct SlabKeyer {
    int axis = 0;
    double lo = 0, inv = 0;
    explicit SlabKeyer(const Box& b) {
        double span = -1;
        for (int d = 0; d < 3; ++d)
            if (b.hi[d] - b.lo[d] > span) span = b.hi[d] - b.lo[d], axis = d;
        lo = b.lo[axis];
        inv = span > 0 ? 1.0 / span : 0.0;
    }
    uint64_t operator()(const double p[3]) const {
        const double s = std::clamp((p[axis] - lo) * inv, 0.0, 1.0);
        return static_cast<uint64_t>(s * double(uint64_t(1) << 62));
    }
};

double extraOf(const PartitionInput& in, int32_t n) { return in.nodeExtraWeight ? in.nodeExtraWeight[n] : 0.0; }

// Node range [begin, end) of piece p, the last piece ending where the input's
// piece table says (nodes past it belong to no piece and are keyed alone).
struct PieceRange {
    int32_t begin, end;
};
PieceRange pieceRange(const PartitionInput& in, int32_t p) { return {in.pieceNodeBegin[p], in.pieceNodeBegin[p + 1]}; }

// Piece of node n, or -1 (binary search in the piece table).
int32_t pieceOf(const PartitionInput& in, int32_t n) {
    if (in.nPieces <= 0 || n < in.pieceNodeBegin[0] || n >= in.pieceNodeBegin[in.nPieces]) return -1;
    const int32_t* b = in.pieceNodeBegin;
    return static_cast<int32_t>(std::upper_bound(b, b + in.nPieces + 1, n) - b) - 1;
}

template <class Keyer>
Partition partitionByKey(const PartitionInput& in, const PartitionOptions& opt, const Keyer& keyOf) {
    const int P = std::max(1, opt.nRanks);
    const int32_t N = in.nNodes;
    Partition part;
    part.nRanks = P;

    // Weight of each piece (its tets plus its nodes' extra weight), which
    // decides whether it is keyed as a whole.  Every tet lies inside one
    // piece, so a quarter per tet node sums to the piece's tet count.
    std::vector<int32_t> place(N, 0);  // tets per node for now; below: node -> position in the order
    for (int64_t t = 0; t < 4 * int64_t(in.nTets); ++t) ++place[in.tetNodes[t]];
    std::vector<double> pieceWeight(std::max(0, in.nPieces), 0.0);
    double total = in.nTets;
    for (int32_t n = 0; n < N; ++n) total += extraOf(in, n);
    for (int32_t p = 0; p < in.nPieces; ++p)
        for (int32_t n = pieceRange(in, p).begin; n < pieceRange(in, p).end; ++n)
            pieceWeight[p] += 0.25 * place[n] + extraOf(in, n);
    const double share = total / P;

    // Keys: a whole piece's nodes all take the key of its centroid, so the
    // sort keeps them together (ties broken by id, and a piece's ids are one
    // range, so nothing else can land between them).
    std::vector<Keyed> order(N);
    std::vector<char> whole(std::max(0, in.nPieces), 0);
    for (int32_t n = 0; n < N; ++n) order[n] = {keyOf(in.pos + 3 * n), n};
    for (int32_t p = 0; p < in.nPieces; ++p) {
        const PieceRange r = pieceRange(in, p);
        if (r.end <= r.begin || pieceWeight[p] > opt.wholePieceFraction * share) continue;
        whole[p] = 1;
        double c[3] = {0, 0, 0};
        for (int32_t n = r.begin; n < r.end; ++n)
            for (int d = 0; d < 3; ++d) c[d] += in.pos[3 * n + d];
        for (int d = 0; d < 3; ++d) c[d] /= (r.end - r.begin);
        const uint64_t k = keyOf(c);
        for (int32_t n = r.begin; n < r.end; ++n) order[n].key = k;
    }
    std::sort(order.begin(), order.end());

    // Weight along the order.  A tet is computed by the lowest owner of its
    // nodes; owners never decrease along the order, so that is the owner of
    // its node that comes first.  Its whole weight goes to that node (not a
    // quarter to each): the cumulative weight between two cuts is then exactly
    // the rank's tets, not off by the half of the tets straddling a cut that
    // the lower rank takes on top of its share.
    for (int32_t j = 0; j < N; ++j) place[order[j].node] = j;
    std::vector<double> prefix(static_cast<std::size_t>(N) + 1, 0.0);  // prefix[j+1]: weight at position j for now
    for (int32_t t = 0; t < in.nTets; ++t) {
        const int32_t* tn = in.tetNodes + 4 * t;
        const int32_t first = std::min(std::min(place[tn[0]], place[tn[1]]), std::min(place[tn[2]], place[tn[3]]));
        prefix[first + 1] += 1;
    }
    for (int32_t j = 0; j < N; ++j) prefix[j + 1] += extraOf(in, order[j].node) + prefix[j];

    // Cuts: cut[r] is the first position of rank r.  Each cut goes where the
    // cumulative weight is nearest k * share; one inside a whole piece moves
    // to the piece's nearer end (else the farther one) when the rank on its
    // left (now known exactly) and the one on its right (up to its ideal end)
    // stay within the tolerance; otherwise the piece is split.
    std::vector<int32_t> cut(P + 1, 0);
    cut[P] = N;
    const double limit = (1 + opt.tolerance) * share;
    for (int k = 1; k < P; ++k) {
        const double target = total * k / P, nextTarget = total * (k + 1) / P;
        int32_t c = static_cast<int32_t>(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
        c = std::min(c, N);
        if (c > 0 && target - prefix[c - 1] <= prefix[c] - target) --c;
        c = std::max(c, cut[k - 1]);
        if (c > 0 && c < N) {
            const int32_t pa = pieceOf(in, order[c - 1].node), pb = pieceOf(in, order[c].node);
            if (pa >= 0 && pa == pb && whole[pa]) {
                const PieceRange r = pieceRange(in, pa);
                int32_t gb = N;
                for (int32_t n = r.begin; n < r.end; ++n) gb = std::min(gb, place[n]);
                const int32_t ge = gb + (r.end - r.begin);
                int32_t cand[2] = {gb, ge};
                if (std::fabs(prefix[ge] - target) < std::fabs(prefix[gb] - target)) std::swap(cand[0], cand[1]);
                for (int32_t x : cand) {
                    if (x < cut[k - 1]) continue;
                    if (prefix[x] - prefix[cut[k - 1]] <= limit && nextTarget - prefix[x] <= limit) {
                        c = x;
                        break;
                    }
                }
            }
        }
        cut[k] = c;
    }

    part.nodeOwner.assign(N, 0);
    part.keyStart.assign(P + 1, std::numeric_limits<uint64_t>::max());
    part.keyStart[0] = 0;
    part.rankWeight.assign(P, 0.0);
    for (int r = 0; r < P; ++r) {
        for (int32_t j = cut[r]; j < cut[r + 1]; ++j) part.nodeOwner[order[j].node] = r;
        if (r > 0 && cut[r] < N) part.keyStart[r] = order[cut[r]].key;
    }
    part.tetOwner.resize(in.nTets);
    for (int32_t t = 0; t < in.nTets; ++t) {
        const int32_t* tn = in.tetNodes + 4 * t;
        const int32_t* o = part.nodeOwner.data();
        part.tetOwner[t] = std::min(std::min(o[tn[0]], o[tn[1]]), std::min(o[tn[2]], o[tn[3]]));
        part.rankWeight[part.tetOwner[t]] += 1;
    }
    for (int32_t n = 0; n < N; ++n) part.rankWeight[part.nodeOwner[n]] += extraOf(in, n);
    return part;
}

}  // namespace

double Partition::imbalance() const {
    double sum = 0, mx = 0;
    const std::size_t from = std::min(rankWeight.size(), static_cast<std::size_t>(std::max(0, firstRank)));
    for (std::size_t r = from; r < rankWeight.size(); ++r) sum += rankWeight[r], mx = std::max(mx, rankWeight[r]);
    if (sum <= 0 || rankWeight.size() == from) return 1.0;
    return mx / (sum / static_cast<double>(rankWeight.size() - from));
}

void shiftRanks(Partition& p, int first) {
    if (first <= 0) return;
    for (int32_t& o : p.nodeOwner) o += first;
    for (int32_t& o : p.tetOwner) o += first;
    p.rankWeight.insert(p.rankWeight.begin(), static_cast<std::size_t>(first), 0.0);
    p.keyStart.insert(p.keyStart.begin(), static_cast<std::size_t>(first), uint64_t(0));  // empty ranges [0, 0)
    p.nRanks += first;
    p.firstRank += first;
}

Partition partitionHilbert(const PartitionInput& in, const PartitionOptions& opt) {
    return partitionByKey(in, opt, HilbertKeyer(boundingBox(in)));
}

Partition partitionSlabs(const PartitionInput& in, const PartitionOptions& opt) {
    return partitionByKey(in, opt, SlabKeyer(boundingBox(in)));
}

int32_t countSplitPieces(const Partition& p, const PartitionInput& in) {
    int32_t split = 0;
    for (int32_t q = 0; q < in.nPieces; ++q) {
        const PieceRange r = pieceRange(in, q);
        for (int32_t n = r.begin + 1; n < r.end; ++n)
            if (p.nodeOwner[n] != p.nodeOwner[r.begin]) {
                ++split;
                break;
            }
    }
    return split;
}

}  // namespace qdem
