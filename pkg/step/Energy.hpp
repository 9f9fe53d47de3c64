// Energy bookkeeping of the QDEM part of a scene.  Signs follow YADE's
// O.energy: the sum of all terms stays constant for an isolated scene, so
// "gravity" is minus the work done by gravity (the potential energy change)
// and dissipation terms grow from zero.
#pragma once

namespace qdem {

struct Energy {
    double kinetic = 0;         // state: 1/2 m v^2 at the integer time level
    double elastic = 0;         // state: strain energy of all tets
    double gravity = 0;         // accumulated: -(work of gravity)
    double viscous = 0;         // accumulated: Kelvin-Voigt dissipation
    double contactElastic = 0;  // state: energy in contact springs
    double contactDamping = 0;  // accumulated: dashpot dissipation
    double friction = 0;        // accumulated: Coulomb slip dissipation
    double boundaryWork = 0;    // accumulated: -(work of moving obstacles, external forces (extForce) and
                                //   blocked DOFs' constraints on the nodes)
    double localDamping = 0;    // accumulated: Cundall's non-viscous damping (when switched on)
    double sleep = 0;           // accumulated: kinetic energy zeroed when pieces fell asleep
    double rigid = 0;           // accumulated: kinetic energy of the deformation modes removed when pieces
                                //   were made rigid (settings.rigidify; their strain energy stays in elastic)

    double total() const {
        return kinetic + elastic + gravity + viscous + contactElastic + contactDamping + friction + boundaryWork +
               localDamping + sleep + rigid;
    }
};

}  // namespace qdem
