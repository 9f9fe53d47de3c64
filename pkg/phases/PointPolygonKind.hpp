// The point-polygon contact kind (seed §3.1): every surface node against the
// surface triangles of the other pieces, with the rules of doc/contacts.md §3.
// It owns its history: kSlots slots per surface node, keyed by stable ids
// (the other piece, and 8 x its local triangle + the feature touched:
// ContactDetail.hpp historyKey), so they survive renumbering (pieces added,
// MPI migration).  Reads the surface triangles the broad phase registers
// (RegisterSurfaceTriangles): the nodes' Verlet lists, or the cell lists.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "ContactKind.hpp"

namespace qdem {

class PointPolygonKind final : public ContactKind {
public:
    static constexpr int kSlots = 6;
    long run(KindStep& s) override;
    void piecesAdded(const PieceContactData& w) override;
    void stateColumns(StateColumns& c) override;
    // States saved before the keys were stable ids (no "eePiece" field) held
    // global triangle ids: converted here.
    void loadFields(const WorldState& s, const PieceContactData& w) override;
    // Cases A/B: interior faces tested for nothing, and of them those within
    // reach; triangles read from the Verlet lists.
    void report(PhaseReport& r) const override;
    void newStep() override { interiorTests_ = interiorNear_ = listed_ = 0; }
    // A contact is the owner's of its node; the triangle's corners lie
    // within reach r_a + r_b <= 2 rMax of the node's closest point on it, and
    // within hMax of that point.
    double haloReach(double rMax, double hMax) const override { return 2 * rMax + 2 * hMax; }
    // `work` per slot holding a contact, on its node.
    void addLoadWeights(const PieceContactData& w, double* perNode, double work) const override;

    const Column<int32_t>& keys() const { return key_; }         // 8 x local triangle + feature; -1 = empty
    const Column<int32_t>& keyPieces() const { return piece_; }  // the other piece

    // The sweep's parts (PointPolygonKind.cpp), each one job of a node's
    // contacts; public for the file's helpers only.
    struct Step;
    struct Thread;
    struct Node;

private:
    Column<int32_t> key_, piece_;
    Column<double> shear_;  // tangential spring (3 per slot)
    Column<double> ref_;    // reference overlap of a contact born deep (0: none), doc/contacts.md §5
    std::vector<long> stamp_;  // per surface node: the step its slots were last used
    long interiorTests_ = 0, interiorNear_ = 0, listed_ = 0;
    template <bool Friction>
    long sweep(KindStep& s);
};

}  // namespace qdem
