// Kinds of contact between pieces, as rows of one table (ContactKinds.cpp).
//
// A row names the kind, says what the broad phase registers for it and how
// its history is laid out, points at its switch (a Settings member) and makes
// its kernel: a ContactKind object that PieceContactPhase runs once per step,
// in table order, after the broad phase (neighbour pieces, their boxes and
// the Verlet/cell lists of the seed's two kinds).  A kind adds its forces on
// surface nodes into the per-thread buffers of KindStep and its energies and
// contact count into the step's tallies; it owns its history (restart
// columns and fields), its counters, and declares its halo reach under MPI
// and its share of the load weights.  Adding a kind: one file with its
// ContactKind class (pkg/phases/*Kind.cpp), one row in ContactKinds.cpp (or
// addContactKind) and its switch line in QDEM_SETTINGS - doc/architecture.md;
// a test-only kind with history is added that way
// (tests/arch/check_kind_files.py counts the files).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "../step/Phase.hpp"
#include "../step/Settings.hpp"
#include "PieceContactData.hpp"

namespace qdem {

struct WorldState;

class PieceContactPhase;
struct PieceContactState;

// What a kind gets and gives in one step.
struct KindStep {
    double dt;
    bool friction;                     // settings.frictionOn
    const PieceContactData& world;     // what the phase declares of the world, read-only to kinds
    // The phase's services to its kinds: which pieces are frozen (asleep
    // among sleepers), the deepest contact per thread, the start check.
    PieceContactPhase& phase;
    const PieceContactState& lists;    // neighbour pieces (nbrStart/nbrs), active pieces, Verlet lists
    // Per thread, 3 per surface node (index into World::surfNodes): the
    // forces this step's kinds add; summed into the nodes after the last kind.
    std::vector<std::vector<double>>& threadForce;
    // Per thread, 2 per surface node: the contacts' stiffness and dashpot
    // load (ContactLoad.hpp), summed with the forces.
    std::vector<std::vector<double>>& threadLoad;
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
    // Its history as restart columns (rows: SurfaceNode or Edge, so MPI
    // migration moves them with their owner), and state that is no column.
    virtual void stateColumns(StateColumns&) {}
    virtual void saveFields(WorldState&) const {}
    virtual void checkFields(const WorldState&) const {}
    virtual void loadFields(const WorldState&, const PieceContactData&) {}
    virtual void report(PhaseReport&) const {}
    // Every step, before any kind runs (or none does): its own counters zeroed.
    virtual void newStep() {}
    // Under MPI, the halo it needs [m]: every node a contact reads lies
    // within this distance of the node whose owner computes the contact.
    // rMax: the largest particle radius; hMax: the longest surface edge.
    virtual double haloReach(double /*rMax*/, double /*hMax*/) const { return 0; }
    // Its share of the partition's load weights (Domain::partitionInput),
    // once per rebalance: `work` per contact of the last step, added to
    // perNode (indexed by node) at the nodes whose owner computes it.
    virtual void addLoadWeights(const PieceContactData&, double* /*perNode*/, double /*work*/) const {}
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
