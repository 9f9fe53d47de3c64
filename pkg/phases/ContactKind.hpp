// Kinds of contact between pieces, as rows of one table (ContactKinds.cpp).
//
// A row names the kind, says what the broad phase registers for it and how
// its history is laid out, points at its switch (a Settings member) and makes
// its kernel: a ContactKind object that PieceContactPhase runs once per step,
// in table order, after the broad phase (neighbour pieces, their boxes and
// the Verlet/cell lists of the seed's two kinds).  A kind adds its forces on
// surface nodes into the per-thread buffers of KindStep and its energies and
// contact count into the step's tallies; it declares its own restart columns
// and counters.  Adding a kind: one file with its ContactKind class, and one
// row (addContactKind, or a line in ContactKinds.cpp) - doc/architecture.md;
// tests/cpp/test_contact_kind_table.cpp adds a test-only kind that way.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "../step/Phase.hpp"
#include "../step/Settings.hpp"
#include "PieceContactData.hpp"

namespace qdem {

class PieceContactPhase;
struct PieceContactState;

// What a kind gets and gives in one step.
struct KindStep {
    double dt;
    bool friction;                     // settings.frictionOn
    const PieceContactData& world;     // what the phase declares of the world, read-only to kinds
    PieceContactPhase& phase;
    const PieceContactState& lists;    // neighbour pieces (nbrStart/nbrs), active pieces, Verlet lists
    // Per thread, 3 per surface node (index into World::surfNodes): the
    // forces this step's kinds add; summed into the nodes after the last kind.
    std::vector<std::vector<double>>& threadForce;
    // Tallies: dissipated by dashpots and sliding [J], largest overlap [m].
    double eDamp = 0, eSlip = 0, maxOverlap = 0;
};

class ContactKind {
public:
    virtual ~ContactKind() = default;
    // The narrow phase: forces into threadForce, energies into the tallies;
    // returns the number of contacts.
    virtual long run(KindStep& s) = 0;
    // Growth of its history with the surfaces (pieces added).
    virtual void piecesAdded(const PieceContactData&) {}
    virtual void stateColumns(StateColumns&) {}
    virtual void report(PhaseReport&) const {}
};

// What a kind needs the broad phase to register (bits of ContactKindRow::lists):
// the phase builds, each step, the lists that some switched-on kind declares
// and no others.
enum Registration : unsigned {
    RegisterNothing = 0,
    // surface triangles near other pieces in cell lists, and each surface
    // node's Verlet list of them (the seed's cases A/B/C: tetrahedra)
    RegisterSurfaceTriangles = 1u << 0,
    // feature edges near other pieces in box grids, and each registered
    // edge's Verlet list of the higher pieces' edges
    RegisterFeatureEdges = 1u << 1,
};

// Which phase runs a kind: the phases keep their places in the step
// (obstacles first, then elements, piece contacts, spheres) and each runs
// the switched-on rows of its family.  Rows of the other families have no
// ContactKind object (make = nullptr): their phase is their kernel, and the
// row gives them their switch, history and counter in the one table.
enum class ContactFamily : int {
    PiecePiece = 0,     // PieceContactPhase: surface nodes and edges of two pieces
    PieceObstacle = 1,  // ObstaclePhase: surface nodes against YADE walls, boxes and facets
    PieceSphere = 2,    // SpherePhase: YADE spheres and clump members against piece surfaces
};

struct ContactKindRow {
    const char* name;       // its counter and timing name
    const char* registers;  // what the broad phase registers for it (in words, for the docs)
    const char* history;    // its contact history (keys by stable ids)
    bool Settings::*on;     // its switch; nullptr: always on
    std::unique_ptr<ContactKind> (*make)();
    unsigned lists = RegisterNothing;  // Registration bits: the broad-phase lists it reads
    ContactFamily family = ContactFamily::PiecePiece;
};

// The table: the seed's point-polygon and edge-edge kinds, the node-obstacle
// and sphere-triangle kinds, then rows added with addContactKind (worlds
// created afterwards run them).
const std::vector<ContactKindRow>& contactKinds();
// The row of a family that has one kind (obstacles, spheres).
const ContactKindRow& contactKind(ContactFamily family);
// Is the kind switched on in these settings?
inline bool kindSwitchedOn(const ContactKindRow& row, const Settings& s) { return !row.on || s.*(row.on); }
void addContactKind(const ContactKindRow& row);
void removeContactKind(const std::string& name);  // (tests)

}  // namespace qdem
