#include "Components.hpp"

#include <numeric>
#include <sstream>

#include "../core/Errors.hpp"

namespace qdem {

namespace {
int32_t findRoot(std::vector<int32_t>& parent, int32_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];  // path halving
        i = parent[i];
    }
    return i;
}
}  // namespace

MeshParts meshParts(const TetMesh& m) {
    const std::size_t nn = m.nNodes(), nt = m.nTets();
    std::vector<int32_t> parent(nn);
    std::iota(parent.begin(), parent.end(), 0);
    for (std::size_t t = 0; t < nt; ++t) {
        const int32_t a = findRoot(parent, m.tets[4 * t]);
        for (int k = 1; k < 4; ++k) {
            const int32_t b = findRoot(parent, m.tets[4 * t + k]);
            if (b != a) parent[b] = a;
        }
    }
    MeshParts parts;
    std::vector<int32_t> label(nn, -1);
    parts.tetPart.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        int32_t& l = label[findRoot(parent, m.tets[4 * t])];
        if (l < 0) {
            l = parts.count++;
            parts.tetCount.push_back(0);
            parts.nodeCount.push_back(0);
        }
        parts.tetPart[t] = l;
        ++parts.tetCount[l];
    }
    std::vector<uint8_t> used(nn, 0);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 4; ++k) {
            const int32_t n = m.tets[4 * t + k];
            if (!used[n]) {
                used[n] = 1;
                ++parts.nodeCount[parts.tetPart[t]];
            }
        }
    return parts;
}

void checkOnePart(const TetMesh& m) {
    const MeshParts p = meshParts(m);
    if (p.count <= 1) return;
    std::ostringstream s;
    s << "mesh: " << p.count << " parts that share no node (sizes: ";
    const int shown = p.count < 6 ? p.count : 6;
    for (int i = 0; i < shown; ++i)
        s << (i ? ", " : "") << p.tetCount[i] << " tets/" << p.nodeCount[i] << " nodes";
    if (shown < p.count) s << ", ...";
    s << "); one piece's parts would not touch each other and would pass through each other. "
         "Use qdem.splitMesh(mesh) and add each part with qdem.addPiece";
    throw InputError(s.str());
}

}  // namespace qdem
