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
#include "../material/Material.hpp"
#include "../world/ContactForces.hpp"
#include "../world/Energy.hpp"
#include "../world/Phase.hpp"
#include "../world/PieceBounds.hpp"
#include "../world/PieceInfo.hpp"
#include "../world/Settings.hpp"

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

private:
    // Per piece that a sphere may touch: its surface triangles binned by
    // centroid, with bounding radii and unit normals of the current shape.
    void buildGrids();
    template <bool Friction>
    void sphereContacts(double dt, double& eEl, double& eDamp, double& eSlip, long& count);
    Data w_;
    long contacts_ = 0;
};

}  // namespace qdem
