// YADE spheres (standalone or clump members) against the surface triangles
// of QDEM pieces: the sphere's centre is a query point with reach R + r
// (doc/spheres.md).  Reads World::spheres (states, filled by the Python
// glue), writes their forceTorque and the nodes' contact forces.
#pragma once
#include <cstdint>
#include <vector>

#include "../contact/SphereSet.hpp"
#include "../contact/SurfaceIndex.hpp"
#include "../core/Column.hpp"
#include "../parallel/DomainRef.hpp"
#include "../material/Material.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../step/PieceBounds.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"

namespace qdem {

class SpherePhase final : public Phase {
public:
    // What it reads and writes of the world.
    struct Data {
        const Column<double>& pos;
        const Column<double>& vel;
        const Column<double>& mass;
        const Column<int32_t>& surfNodes;
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const long& iter;                  // the step contacts are stamped with
        const SurfaceIndex& surface;
        const PieceBounds& bounds;         // which pieces a sphere can touch
        DomainRef domain;                  // under MPI: who computes a (sphere, piece) pair
        SphereSet& spheres;                // states in, forces and torques out, contact history
        ContactForces& contacts;
        Energy& energy;                    // contact elastic (a state), damping, friction
    };
    explicit SpherePhase(const Data& data) : w_(data) {}
    const char* name() const override { return "spheres"; }
    void run(double dt) override;
    void report(PhaseReport& r) const override {
        Phase::report(r);
        r.counts.push_back({"sphere", contacts_});  // YADE sphere - QDEM surface contacts
    }
    // World::setSpheres: the spheres that may touch pieces, with their
    // (sphere, piece) contact history carried over.
    void setSpheres(int32_t n, const int32_t* id, const double* radius, const double* young, const double* ktRatio,
                    const double* friction, const double* restitution, const double* mass, const int32_t* pairStart,
                    const int32_t* pairPiece);

    // ---- under MPI (doc/parallel.md, "YADE spheres") --------------------------
    // Every rank holds every sphere (YADE's scene is replicated); a (sphere,
    // piece) pair is computed by the owner of the lowest-id node of the
    // triangles within its reach, and its force, torque and history reach
    // every rank through the end-of-step reduction (Domain::finishStep), so
    // every rank's copy of YADE applies the same force.
    // The pairs whose sphere box meets the piece's (whole) box: the same list
    // on every rank.  Called every step before the phases, never throws.
    void listActive();
    static constexpr int kPairValues = 7 + 5 * SphereSet::kSlots;  // flag, F, T, key + 1, ref, shear
    std::size_t mpiValues() const;
    void packPairs(double* out) const;
    // The sums over the ranks: every rank takes the owner's results; throws
    // StabilityError if a pair was computed on two ranks.  `phaseIter`: the
    // step the phase ran at.
    void unpackPairs(const double* in, long phaseIter);

    // Restarts: the (sphere id, piece) pairs' contact histories.
    void saveFields(WorldState& s) const override;
    void checkFields(const WorldState& s) const override;
    void loadFields(const WorldState& s) override;

private:
    // A contact history by (sphere id, piece): what setSpheres carries over.
    struct History {
        std::vector<int32_t> id, pairStart, pairPiece, key;
        std::vector<double> shear, ref;
        std::vector<long> stamp;
    };
    void carry(const History& old);
    History loaded_;  // from a restart, for the next setSpheres
    bool hasLoaded_ = false;
    // forceTorque of each sphere: its pairs' parts summed in pair order
    // (the same sum serially and on every rank).
    void sumPairForces();
    // Per piece that a sphere may touch: its surface triangles binned by
    // centroid, with bounding radii and unit normals of the current shape.
    void buildGrids();
    template <bool Friction>
    void sphereContacts(double dt, double& eEl, double& eDamp, double& eSlip, long& count);
    Data w_;
    long contacts_ = 0;
};

}  // namespace qdem
