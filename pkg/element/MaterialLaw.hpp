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
// Adding a law: its file in laws/ (a class named as its tag), one line of
// QDEM_MATERIAL_LAWS (pkg/material/Material.hpp) and its #include here; the
// dispatch below, the names, the Python QdemMat and the tests follow the list.
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
#define QDEM_LAW_CASE(Tag, name, doc) \
    case MaterialLaw::Tag: return f(Tag(m.lambda(), m.mu()));
        QDEM_MATERIAL_LAWS(QDEM_LAW_CASE)
#undef QDEM_LAW_CASE
    }
    // Material::validate refuses any other tag; the default law, should one get here.
    return f(StableNeoHookean(m.lambda(), m.mu()));
}

}  // namespace qdem
