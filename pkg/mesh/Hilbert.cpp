#include "Hilbert.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

namespace qdem {

namespace {
constexpr int kBits = 21;

// Skilling's transform (AIP Conf. Proc. 707, 2004): axes -> transposed Hilbert index.
void axesToTranspose(uint32_t X[3]) {
    const uint32_t M = 1u << (kBits - 1);
    for (uint32_t Q = M; Q > 1; Q >>= 1) {
        const uint32_t P = Q - 1;
        for (int i = 0; i < 3; ++i) {
            if (X[i] & Q) {
                X[0] ^= P;
            } else {
                const uint32_t t = (X[0] ^ X[i]) & P;
                X[0] ^= t;
                X[i] ^= t;
            }
        }
    }
    for (int i = 1; i < 3; ++i) X[i] ^= X[i - 1];
    uint32_t t = 0;
    for (uint32_t Q = M; Q > 1; Q >>= 1)
        if (X[2] & Q) t ^= Q - 1;
    for (int i = 0; i < 3; ++i) X[i] ^= t;
}
}  // namespace

uint64_t hilbertKey(const double p[3], const double lo[3], const double hi[3]) {
    uint32_t X[3];
    const double maxCoord = double((1u << kBits) - 1);
    for (int d = 0; d < 3; ++d) {
        const double span = hi[d] - lo[d];
        double s = span > 0 ? (p[d] - lo[d]) / span : 0.0;
        s = std::clamp(s, 0.0, 1.0);
        X[d] = static_cast<uint32_t>(s * maxCoord);
    }
    axesToTranspose(X);
    uint64_t key = 0;
    for (int b = kBits - 1; b >= 0; --b)
        for (int d = 0; d < 3; ++d) key = (key << 1) | ((X[d] >> b) & 1u);
    return key;
}

std::vector<int32_t> hilbertReorder(TetMesh& m, std::vector<int32_t>* tetOldOf) {
    const std::size_t nn = m.nNodes(), nt = m.nTets();
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        lo[d] = std::numeric_limits<double>::max();
        hi[d] = std::numeric_limits<double>::lowest();
    }
    for (std::size_t i = 0; i < nn; ++i)
        for (int d = 0; d < 3; ++d) {
            lo[d] = std::min(lo[d], m.nodes[3 * i + d]);
            hi[d] = std::max(hi[d], m.nodes[3 * i + d]);
        }
    std::vector<uint64_t> key(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; ++k)
            for (int d = 0; d < 3; ++d) c[d] += 0.25 * m.nodes[3 * m.tets[4 * t + k] + d];
        key[t] = hilbertKey(c, lo, hi);
    }
    std::vector<int32_t> order(nt);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] < key[b]; });

    std::vector<int32_t> newId(nn, -1), oldOf;
    oldOf.reserve(nn);
    std::vector<int32_t> tets(4 * nt);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 4; ++k) {
            const int32_t old = m.tets[4 * order[t] + k];
            if (newId[old] < 0) {
                newId[old] = static_cast<int32_t>(oldOf.size());
                oldOf.push_back(old);
            }
            tets[4 * t + k] = newId[old];
        }
    for (std::size_t i = 0; i < nn; ++i)
        if (newId[i] < 0) {
            newId[i] = static_cast<int32_t>(oldOf.size());
            oldOf.push_back(static_cast<int32_t>(i));
        }
    std::vector<double> nodes(3 * nn);
    for (std::size_t i = 0; i < nn; ++i)
        for (int d = 0; d < 3; ++d) nodes[3 * i + d] = m.nodes[3 * oldOf[i] + d];
    m.nodes.swap(nodes);
    m.tets.swap(tets);
    if (tetOldOf) *tetOldOf = std::move(order);
    return oldOf;
}

}  // namespace qdem
