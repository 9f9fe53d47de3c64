// The edge-edge contact kind (seed §3.2): feature edges of different pieces
// whose closest points lie inside both edges, with the fades and side memory
// of doc/contacts.md §4.  It owns its history: kSlots slots per surface edge
// (held by the lower piece's edge: each pair once), keyed by stable ids (the
// other edge's piece and its id within that piece).  Reads the feature edges
// the broad phase registers (RegisterFeatureEdges): each registered edge's
// Verlet list, or the box grids.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "ContactKind.hpp"

namespace qdem {

class EdgeEdgeKind final : public ContactKind {
public:
    static constexpr int kSlots = 4;
    long run(KindStep& s) override;
    void piecesAdded(const PieceContactData& w) override;
    void stateColumns(StateColumns& c) override;
    // The partners' pieces are a field (states saved before the keys were
    // stable ids lack it: their global edge ids are converted on loading).
    void saveFields(WorldState& s) const override;
    void checkFields(const WorldState& s) const override;
    void loadFields(const WorldState& s, const PieceContactData& w) override;
    // A pair is the owner's of its edge's lower node; the other edge's ends
    // lie within reach r_a + r_b <= 2 rMax of the closest points, each within
    // an edge length hMax of them.
    double haloReach(double rMax, double hMax) const override { return 2 * rMax + 2 * hMax; }

    // The sweep's parts (EdgeEdgeKind.cpp); public for the file's helpers only.
    struct Step;
    struct Thread;
    struct Edge;

private:
    Column<int32_t> other_, piece_;  // the other edge: local edge id, piece; -1 = empty
    Column<int8_t> side_;            // the side of the other edge this one is on (+-1; 0: none yet)
    Column<double> shear_;           // tangential spring (3 per slot), times sqrt(w aw)
    Column<double> ref_;             // reference overlap of a contact born deep (0: none)
    std::vector<long> stamp_;        // per surface edge: the step its slots were last used
    template <bool Friction>
    long sweep(KindStep& s);
};

}  // namespace qdem
