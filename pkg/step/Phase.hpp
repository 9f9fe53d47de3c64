// One stage of World::step, with the state it owns.
//
// A phase is run once per step (a virtual call per phase and step, never per
// node or contact).  It sees no World: each phase class declares, as its
// nested `Data`, the arrays and objects it reads (const) and writes, and the
// world hands it those at construction (World.hpp).  A phase therefore
// cannot reach into data it does not declare; pkg/phases/*.cpp include no
// World.hpp (tests/cpp/test_phase_data.cpp checks that).  In the phases,
// `w_` is that declared part of the world.
//
// A phase declares what a restart must keep of its state (stateColumns:
// named arrays that Checkpoint.cpp saves and loads without knowing the
// phase), grows its per-node and per-piece state when pieces are added, and
// is told when a loaded state replaced its arrays.
#pragma once
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace qdem {

struct WorldState;

// What the phases measured in the last step: wall times [s] and counters,
// by name (World::timings, World::counts; the Python dicts of the same names).
struct PhaseReport {
    std::vector<std::pair<const char*, double>> seconds;
    std::vector<std::pair<const char*, long>> counts;
    double second(const std::string& name) const {
        for (const auto& [n, v] : seconds)
            if (name == n) return v;
        return 0;
    }
    long count(const std::string& name) const {
        for (const auto& [n, v] : counts)
            if (name == n) return v;
        return 0;
    }
};

// Named arrays of a phase's state, by reference, for Checkpoint.cpp and for
// migration between MPI ranks (Domain::rebalance): what each row belongs to
// says which rank holds the true row (the owner of that node, surface node,
// or of the edge's lower node: the rank computing its edge-edge contacts).
enum class Rows { Node, SurfaceNode, Edge, Other };

struct StateColumns {
    struct Ref {
        std::string name;
        void* data;
        std::size_t count;     // values
        std::size_t elemSize;  // bytes per value
        Rows rows;
        bool restart;          // saved in restarts (false: only migrated)
    };
    std::vector<Ref> refs;
    template <class C>
    void add(const char* name, C& column, Rows rows = Rows::Other, bool restart = true) {
        refs.push_back({name, static_cast<void*>(column.data()), column.size(), sizeof(*column.data()), rows, restart});
    }
};

class Phase {
public:
    Phase() = default;
    virtual ~Phase() = default;
    Phase(const Phase&) = delete;
    Phase& operator=(const Phase&) = delete;

    virtual const char* name() const = 0;
    // One step's work.
    virtual void run(double dt) = 0;
    // Its wall time (World::step measures it) and counters, by name: the
    // phase's own name unless it splits its time further.
    virtual void report(PhaseReport& r) const { r.seconds.push_back({name(), seconds}); }
    double seconds = 0;  // wall time of the last run [s]
    // What a restart must keep of this phase's state (none by default).
    virtual void stateColumns(StateColumns&) {}
    // Pieces were added: grow per-node / per-piece state (new entries empty).
    virtual void piecesAdded() {}
    // State that is not a column (lists of lists, flags with defaults for
    // older files): written to and read from the state by name.  checkFields
    // throws InputError before anything changes when the state does not fit.
    virtual void saveFields(WorldState&) const {}
    virtual void checkFields(const WorldState&) const {}
    virtual void loadFields(const WorldState&) {}
    // A saved state was loaded (columns and fields): derived data is stale.
    virtual void stateLoaded() {}
    // The partition's load weights (Domain::partitionInput), once per
    // rebalance: `work` per contact of the last step, added to perNode
    // (indexed by node) at the nodes whose owner computes the contact.
    virtual void addLoadWeights(double* /*perNode*/, double /*work*/) const {}
};

}  // namespace qdem
