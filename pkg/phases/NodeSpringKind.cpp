// A test-only contact kind with history (doc/architecture.md, "Add a contact
// kind"): a bond between two surface nodes of different pieces, born when they
// come within the contact reach R = r_a + r_b, with the distance at birth d0
// as its rest length, pulling or pushing f = k (d - d0) along the line of
// centres, k = E_min r_min / 10, until stretched to R (it breaks).  Its
// history - the other node (piece, surface node within that piece) and d0 -
// is keyed by stable ids, kept per surface node, saved in restarts (as
// fields: older files load with no bonds) and moved with its node between
// MPI ranks.  It is switched off by default
// (QdemEngine.nodeSpringTest): it exists to prove that a kind with history
// is one file, one row and one switch line (tests/arch/check_kind_files.py,
// tests/cpp/test_contact_kind_history.cpp, tests/python/test_mpi_contact_kind_history.py).
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "../core/Column.hpp"
#include "../parallel/Domain.hpp"
#include "../step/WorldState.hpp"
#include "ContactKind.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

namespace {

class NodeSpringKind final : public ContactKind {
public:
    static constexpr int kSlots = 4;

    // Each pair once: a node of the lower piece queries the higher piece's
    // surface nodes, on the rank owning it (its slots hold the bond).  One
    // thread: the kind is a proof, not a kernel to be fast.
    long run(KindStep& s) override {
        const PieceContactData& w = s.world;
        const PieceContactState& L = s.lists;
        const Domain* dom = w.domain.built();
        const uint8_t* cur = dom ? dom->currentMask().data() : nullptr;
        const uint8_t* frozen = s.phase.frozenFlags();
        double* buf = s.threadForce[0].data();
        long n = 0;
        for (std::size_t pa = 0; pa < w.pieces.size(); ++pa)
            for (int32_t i = w.pieces[pa].surfBegin; i < w.pieces[pa].surfEnd; ++i) {
                const int32_t a = w.surfNodes[i];
                if (dom && !dom->owns(a)) continue;
                int32_t* other = &other_[kSlots * i];
                int32_t* otherPiece = &piece_[kSlots * i];
                double* rest = &rest_[kSlots * i];
                if (frozen[pa]) {  // asleep among sleeping pieces: bonds kept
                    stamp_[i] = w.iter;
                    continue;
                }
                if (stamp_[i] != w.iter - 1)  // history is only valid from the previous step
                    for (int k = 0; k < kSlots; ++k) other[k] = -1, otherPiece[k] = -1;
                stamp_[i] = w.iter;
                int32_t newOther[kSlots], newPiece[kSlots];
                double newRest[kSlots];
                int nNew = 0;
                for (int32_t q = L.nbrStart[pa]; q < L.nbrStart[pa + 1]; ++q) {
                    const auto pb = static_cast<std::size_t>(L.nbrs[q]);
                    if (pb < pa) continue;
                    const Material& ma = w.materials[w.pieces[pa].material];
                    const Material& mb = w.materials[w.pieces[pb].material];
                    const double R = ma.radius + mb.radius;
                    const double k = 0.1 * std::min(ma.young, mb.young) * std::min(ma.radius, mb.radius);
                    for (int32_t j = w.pieces[pb].surfBegin; j < w.pieces[pb].surfEnd && nNew < kSlots; ++j) {
                        const int32_t b = w.surfNodes[j];
                        if (cur && !cur[b]) continue;
                        double d[3], d2 = 0;
                        for (int c = 0; c < 3; ++c) d[c] = w.pos[3 * a + c] - w.pos[3 * b + c], d2 += d[c] * d[c];
                        const double dist = std::sqrt(d2);
                        if (dist >= R || dist == 0) continue;
                        const int32_t local = j - w.pieces[pb].surfBegin;
                        double d0 = dist;  // born now: at rest
                        for (int m = 0; m < kSlots; ++m)
                            if (other[m] == local && otherPiece[m] == static_cast<int32_t>(pb)) d0 = rest[m];
                        const double f = -k * (dist - d0) / dist;
                        for (int c = 0; c < 3; ++c) buf[3 * i + c] += f * d[c], buf[3 * j + c] -= f * d[c];
                        newOther[nNew] = local, newPiece[nNew] = static_cast<int32_t>(pb), newRest[nNew] = d0;
                        ++nNew, ++n;
                    }
                }
                for (int m = 0; m < kSlots; ++m) {
                    other[m] = m < nNew ? newOther[m] : -1;
                    otherPiece[m] = m < nNew ? newPiece[m] : -1;
                    rest[m] = m < nNew ? newRest[m] : 0.0;
                }
            }
        return n;
    }

    void piecesAdded(const PieceContactData& w) override {
        const std::size_t ns = w.surfNodes.size();
        stamp_.resize(ns, -2);
        other_.resize(kSlots * ns, -1);
        piece_.resize(kSlots * ns, -1);
        rest_.resize(kSlots * ns, 0.0);
    }
    // Migrated with their nodes (columns), saved in restarts as fields: a
    // state saved without this kind (an older file) loads with no bonds.
    void stateColumns(StateColumns& c) override {
        c.add("nsOther", other_, Rows::SurfaceNode, false);
        c.add("nsPiece", piece_, Rows::SurfaceNode, false);
        c.add("nsRest", rest_, Rows::SurfaceNode, false);
        c.add("nsStamp", stamp_, Rows::SurfaceNode, false);
    }
    void saveFields(WorldState& s) const override {
        s.put("nsOther", other_.data(), other_.size());
        s.put("nsPiece", piece_.data(), piece_.size());
        s.put("nsRest", rest_.data(), rest_.size());
        s.put("nsStamp", stamp_.data(), stamp_.size());
    }
    void checkFields(const WorldState& s) const override {
        if (s.fields.count("nsOther") == 0) return;
        s.check<int32_t>("nsOther", other_.size());
        s.check<int32_t>("nsPiece", piece_.size());
        s.check<double>("nsRest", rest_.size());
        s.check<long>("nsStamp", stamp_.size());
    }
    void loadFields(const WorldState& s, const PieceContactData&) override {
        if (s.fields.count("nsOther") == 0) {
            other_.fill(-1);
            std::fill(stamp_.begin(), stamp_.end(), -2);
            return;
        }
        s.get("nsOther", other_.data(), other_.size());
        s.get("nsPiece", piece_.data(), piece_.size());
        s.get("nsRest", rest_.data(), rest_.size());
        s.get("nsStamp", stamp_.data(), stamp_.size());
    }
    // The other node lies within R <= 2 rMax of the querying one.
    double haloReach(double rMax, double /*hMax*/) const override { return 2 * rMax; }
    void addLoadWeights(const PieceContactData& w, double* perNode, double work) const override {
        for (std::size_t i = 0; i < w.surfNodes.size(); ++i)
            for (int m = 0; m < kSlots; ++m)
                if (other_[kSlots * i + m] >= 0) perNode[w.surfNodes[i]] += work;
    }

private:
    Column<int32_t> other_, piece_;  // the other node: its index among its piece's surface nodes, its piece
    Column<double> rest_;            // the bond's rest length d0 [m]
    std::vector<long> stamp_;        // per surface node: the step its slots were last used
};

}  // namespace

std::unique_ptr<ContactKind> makeNodeSpringKind() { return std::make_unique<NodeSpringKind>(); }

}  // namespace qdem
