// YADE spheres (standalone or clump members) against the surface triangles
// of QDEM pieces: the sphere's centre is a query point with reach R + r
// (doc/spheres.md).  Reads World::spheres (states, filled by the Python
// glue), writes their forceTorque and the nodes' contact forces.
#pragma once
#include <cstdint>

#include "../world/Phase.hpp"

namespace qdem {

class SpherePhase final : public Phase {
public:
    using Phase::Phase;
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
    long contacts_ = 0;
};

}  // namespace qdem
