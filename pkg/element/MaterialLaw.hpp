// The material-law interface.  A law is a small struct (laws/*.hpp) built
// from the small-strain Lame constants (lambda, mu) that gives
//   lane<Viscous, Energy>(F, sS_v, s, sP, w, aux)  the SIMD-lane stress, scaled
//                                              by s = -V0, and energy,
//   energyFinish(aux)                          a scalar energy term (log etc.),
//   piola(F), energy(F), tangent(F)            reference forms (dP/dF 9x9),
//   tangentChangeBound(F, s1)                  bound of ||dP/dF(F) - dP/dF(I)||,
//   kRecoversFromInversion                     whether J <= 0 is pushed back.
// withLaw() turns the Material's tag into that type once per call (once per
// tet segment in the step), so hot loops are templated, never virtual.
// Adding a law: one file in laws/, one enum value (Material.hpp), one case
// here, one name in py/qdem/material.py.
#pragma once
#include "../core/Errors.hpp"
#include "../material/Material.hpp"
#include "laws/SaintVenantKirchhoff.hpp"
#include "laws/StableNeoHookean.hpp"

namespace qdem {

// Calls f(law) with the law object of material m.
template <class Fn>
decltype(auto) withLaw(const Material& m, Fn&& f) {
    switch (m.law) {
        case MaterialLaw::SaintVenantKirchhoff: return f(SaintVenantKirchhoff(m.lambda(), m.mu()));
        case MaterialLaw::StableNeoHookean: break;
    }
    return f(StableNeoHookean(m.lambda(), m.mu()));
}

}  // namespace qdem
