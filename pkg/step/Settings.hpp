// Every switch and number of the QDEM step, declared once.
//
// One line of QDEM_SETTINGS per setting: its C++ type and member name, the
// name users see on QdemEngine (empty: not an engine attribute), its default,
// the values it may take, and its docstring.  From this list come the members
// of Settings (what the phases read), the Python properties of the core World
// with their checks and docstrings, and the attributes of QdemEngine with
// their defaults shown in help() (py/bindings/bind_settings.cpp,
// py/qdem/yade/engine.py).  Adding a setting is one line here.
#pragma once
#include <cmath>
#include <string>
#include <vector>

namespace qdem {

// Tangential law of every contact (ContactLaw.hpp).
enum class FrictionModel : int { Spring = 0, Regularized = 1 };

// How surface elements are registered in the cell list.  The seed paper's
// Figure 6 compares A, B and C; Triangles is ours and the default.
enum class BroadPhase : int {
    Triangles = 0,    // surface triangles only, binned by their own size
    AllTets = 1,      // A: every tetrahedron, all four faces tested
    SurfaceTets = 2,  // B: surface tetrahedra only, all four faces tested
    SurfaceFaces = 3  // C: surface tetrahedra only, interior faces skipped
};

// How the Kelvin-Voigt viscous force is integrated (ViscousSolve.hpp).
enum class ViscousIntegration : int { Explicit = 0, Implicit = 1 };
// The implicit viscous solve's preconditioner (CorotatedCholesky.hpp).
enum class ViscousPreconditioner : int { Jacobi = 0, Cholesky = 1 };

// What values a setting may take: any (bool), a closed or half-open range,
// or named choices (enums; the index is the enum's value).
struct SettingRange {
    double lo = -INFINITY, hi = INFINITY;
    bool hiOpen = false;  // [lo, hi) rather than [lo, hi]
    bool loOpen = false;  // (lo, hi]
    std::vector<std::string> choices;
    std::string note;  // said with a refusal (an angle's unit)
    SettingRange withNote(std::string n) const {
        SettingRange r = *this;
        r.note = std::move(n);
        return r;
    }
};

// Angles are in radians; a refusal says so (30, meant as degrees, was taken
// as 30 rad: for edgeFeatureAngle a cosine's wrap, ~81 degrees).
inline constexpr const char* kRadians = "an angle in radians (30 degrees is 0.5236)";

inline SettingRange anyValue() { return {}; }
inline SettingRange atLeast(double lo) { return {lo, INFINITY, false, false, {}, {}}; }
inline SettingRange positive() { return {0, INFINITY, false, true, {}, {}}; }
inline SettingRange within(double lo, double hi) { return {lo, hi, false, false, {}, {}}; }
inline SettingRange withinOpenTop(double lo, double hi) { return {lo, hi, true, false, {}, {}}; }
inline SettingRange oneOf(std::vector<std::string> names) {
    return {-INFINITY, INFINITY, false, false, std::move(names), {}};
}

// X(type, member, engineName, default, range, doc)
#define QDEM_SETTINGS(X)                                                                                              \
    X(bool, trackEnergy, "", false, anyValue(),                                                                      \
      "Sum the energy ledger each step (QdemEngine takes it from O.trackEnergy).")                                   \
    X(bool, viscosityOn, "viscosity", true, anyValue(),                                                              \
      "Apply the Kelvin-Voigt viscous stress (False switches it off).")                                              \
    X(ViscousIntegration, viscousIntegration, "viscousIntegration", ViscousIntegration::Explicit,                   \
      oneOf({"explicit", "implicit"}),                                                                               \
      "How the Kelvin-Voigt viscous force is integrated: 'explicit' (default: with the velocity of the last half "  \
      "step, as every other force; the stable step shrinks as h^2 with viscosity) or 'implicit' (each step solves " \
      "(M + dt C) v = M v_old + dt f for the new velocities by conjugate gradients: viscosity no longer limits "    \
      "O.dt, elasticity and contacts stay explicit; under MPI too).  doc/formulation.md, section 2.1.")            \
    X(double, viscousTolerance, "viscousTolerance", 1e-3, within(1e-14, 0.5),                                        \
      "viscousIntegration='implicit': the conjugate gradients stop when the error of the step's velocity change "    \
      "is at most this fraction of that change (kinetic-energy norm; a bound, doc/formulation.md 2.1).")           \
    X(bool, viscousWarmStart, "viscousWarmStart", true, anyValue(),                                                 \
      "viscousIntegration='implicit': start each step's conjugate gradients from the last step's velocity change "  \
      "(2-5 times fewer iterations on smooth motion).  Each step's error stays within viscousTolerance, but it "    \
      "carries into the next step's start, so runs differing only in rounding (thread counts, MPI ranks) drift "    \
      "apart within that tolerance; False starts from zero: results that depend on the state alone and agree to "  \
      "rounding.  doc/formulation.md 2.1.")                                                                          \
    X(ViscousPreconditioner, viscousPreconditioner, "viscousPreconditioner", ViscousPreconditioner::Cholesky,       \
      oneOf({"jacobi", "cholesky"}),                                                                                 \
      "viscousIntegration='implicit': the conjugate gradients' preconditioner.  'cholesky' (default): per piece, "  \
      "M + dt C of the reference shape factored once (refactored when dt changes by more than 1 % or the "          \
      "material, masses or mesh change) and applied rotated with the piece's best-fit rotation: 1-3 iterations a "  \
      "step where Jacobi takes tens.  'jacobi': the diagonal of M + dt C (no factor to store).  They give the "      \
      "same answer within viscousTolerance, not the same bits.  doc/formulation.md 2.1.")                          \
    X(double, localDamping, "damping", 0.0, withinOpenTop(0, 1),                                                     \
      "Cundall's non-viscous local damping of QDEM nodes, as NewtonIntegrator.damping (which QDEM does not "         \
      "inherit): for quasi-static problems; 0 keeps the dynamics exact.")                                            \
    X(bool, frictionOn, "friction", true, anyValue(),                                                                \
      "Apply tangential (friction) contact forces (False switches them off).")                                       \
    X(FrictionModel, frictionModel, "frictionModel", FrictionModel::Spring, oneOf({"spring", "regularized"}),       \
      "Tangential contact law: 'spring' (Cundall-Strack spring with a Coulomb cap: sticks below the friction "       \
      "angle, the default) or 'regularized' (Ft = -mu Fn vt/max(|vt|, frictionRegVelocity), no history: creeps "    \
      "on slopes at frictionRegVelocity tan(theta)/mu). doc/accuracy.md compares them.")                             \
    X(double, frictionRegVelocity, "frictionRegVelocity", 1e-3, positive(),                                          \
      "Slip speed [m/s] at which the 'regularized' friction law reaches mu*Fn.")                                     \
    X(bool, pointPolygonOn, "pointPolygon", true, anyValue(), "Point-polygon contacts between pieces (seed paper 3.1).") \
    X(bool, pointPolygonRegions, "pointPolygonRegions", true, anyValue(),                                            \
      "Point-polygon closest points in the edge and vertex regions of the triangles too (default), so a node "      \
      "over a convex ridge or corner of the other piece keeps its contact; False: the seed's inside test (3.1: "    \
      "the projection must fall inside the triangle).")                                                              \
    X(bool, edgeEdgeOn, "edgeEdge", true, anyValue(),                                                                \
      "Edge-edge contacts between pieces (seed paper 3.2, with friction).")                                          \
    X(BroadPhase, broadPhase, "broadPhase", BroadPhase::Triangles, oneOf({"triangles", "A", "B", "C"}),             \
      "How surface elements are registered in the cell list: 'triangles' (default), or the seed's Figure 6 "       \
      "cases 'A' (all tets), 'B' (surface tets), 'C' (surface tets, interior faces skipped).")                      \
    X(double, edgeFadeAngle, "edgeFadeAngle", 0.17453292519943295, within(1e-6, 1.5707963267948966).withNote(kRadians), \
      "Edge-edge forces fade out as edges become parallel (the point-polygon contacts at their ends carry such "    \
      "a contact): full at or above this angle [rad] between the edges, zero when parallel.")                       \
    X(double, edgeFeatureAngle, "edgeFeatureAngle", 0.5235987755982988,                                              \
      within(0, 3.141592653589793).withNote(kRadians),                                                             \
      "Edge-edge contacts are sought between feature edges only: those whose two faces meet at more than this "     \
      "angle [rad] in the reference shape (0 to pi; pi: none).")                                                    \
    X(double, verletSkin, "verletSkin", 0.5, atLeast(0),                                                             \
      "Verlet-list skin of the default broad phase, as a fraction of the largest particle radius: larger = "        \
      "rarer rebuilds, longer lists.")                                                                               \
    X(int, verletRebuildSteps, "verletRebuildSteps", 4, within(1, 64),                                               \
      "A Verlet-list rebuild is spread over this many steps (1: all in one step): the first registers and bins "    \
      "the surface triangles, the second the feature edges with their lists, and the second to last build the "    \
      "nodes' lists a part each, while the nodes not yet done keep their former lists, which are still valid "     \
      "(the rebuild starts early enough; if motion outruns it, the rest is built at once).  Same contacts; no "    \
      "step pays the whole rebuild (at 4, the 27-cube scene's dearest rebuild step is ~1.1x an ordinary one: "  \
      "doc/performance.md).  1 under MPI.")                                                                  \
    X(double, sleepVelocity, "sleepVelocity", 0.0, atLeast(0),                                                       \
      "Pieces at rest sleep: one whose nodes all stay slower than this [m/s] for sleepTime, with no faster piece "  \
      "near it, is left out of the step (zero velocity, no element or contact work; its push on obstacles kept) "   \
      "until a neighbour piece moves faster than this, an obstacle near it moves or a sphere comes near.  0 "       \
      "(default) = never.  doc/sleeping.md: choice and error.")                                                      \
    X(double, sleepTime, "sleepTime", 0.01, atLeast(0),                                                              \
      "How long [s] a piece must stay slower than sleepVelocity before it sleeps.")                                \
    X(double, rebalanceThreshold, "rebalance", 1.15, atLeast(0),                                                     \
      "Under MPI: the nodes are split again along the Hilbert curve (with their contact histories) when the "     \
      "largest rank's load exceeds this multiple of the mean (load = owned tetrahedra + contactWork x contacts). " \
      "0 = never.  doc/parallel.md.")                                                                                \
    X(double, contactWork, "contactWork", 4.0, atLeast(0),                                                           \
      "Under MPI: the work of one contact in units of one tetrahedron's, for the load that balances the ranks.")   \
    X(bool, rigidify, "rigidify", false, anyValue(),                                                                 \
      "Adaptive rigidity: a piece whose strain-rate estimate stays below rigidStrainRate for rigidTime moves as a "  \
      "rigid body in its current deformed shape (6 DOF; its surface nodes keep their contacts; no element pass, no " \
      "viscous solve) until a change of the load on it would strain it (rigidWakeLoad, rigidWakeStrain).  Changes " \
      "the physics: off by "                                                                                         \
      "default; doc/accuracy.md 'Adaptive rigidity' gives its error and gain.  Not under MPI.")                     \
    X(double, rigidStrainRate, "rigidStrainRate", 0.1, positive(),                                                   \
      "rigidify: the strain rate [1/s] below which a piece may become rigid; estimated as the largest deviation of " \
      "its node velocities from their best rigid-body fit over its smallest reference edge (doc/formulation.md, "   \
      "'Adaptive rigidity').")                                                                                        \
    X(double, rigidTime, "rigidTime", 0.002, atLeast(0),                                                             \
      "rigidify: how long [s] a piece's strain-rate estimate must stay below rigidStrainRate before it is made "    \
      "rigid.")                                                                                                       \
    X(double, rigidWakeLoad, "rigidWakeLoad", 0.1, positive(),                                                       \
      "rigidify: a rigid piece becomes deformable again when the load deforming it (its nodes' forces less their "  \
      "share of the rigid acceleration, in the body frame) differs from the one it was made rigid under by more "   \
      "than this fraction of max(that load, its weight), summed over its nodes (dimensionless), and that change "   \
      "would strain it by more than rigidWakeStrain.")                                                             \
    X(double, rigidWakeStrain, "rigidWakeStrain", 1e-5, atLeast(0),                                                  \
      "rigidify: a rigid piece becomes deformable again only when the change of the load deforming it would "      \
      "strain it by more than this (dimensionless): the change summed over its nodes, over 2 E A (E its softest "   \
      "Young modulus, A its volume over its largest extent).  A piece rocking on its support shifts about its "     \
      "weight (strain ~ rho g l / E) and stays rigid; a hit at speed v strains it far more.  0 = the load test "   \
      "alone (doc/formulation.md, 'Adaptive rigidity').")  \
    X(bool, nodeSpringTestOn, "nodeSpringTest", false, anyValue(),                                                   \
      "A test-only contact kind between pieces (doc/architecture.md, 'Add a contact kind'): surface nodes of "      \
      "different pieces closer than r_a + r_b bond at their distance then, with a spring k = E r / 10 [N/m] that "  \
      "breaks when stretched to r_a + r_b. Not a physical model: it proves a kind with history is one file.")  \
    X(bool, obstaclesOn, "couple", true, anyValue(),                                                                 \
      "Couple QDEM nodes to YADE Wall, Box and Facet bodies (scanned again whenever the number of bodies "          \
      "changes): the contact kind 'wall' of the contact-kinds table.")                                               \
    X(bool, spheresOn, "spheres", true, anyValue(),                                                                  \
      "Couple QDEM pieces with YADE spheres and clump members (doc/spheres.md): needs an InsertionSortCollider in "  \
      "O.engines, before this engine.  The contact kind 'sphere' of the contact-kinds table.")

struct Settings {
#define QDEM_SETTING_MEMBER(T, name, engineName, def, range, doc) T name = def;
    QDEM_SETTINGS(QDEM_SETTING_MEMBER)
#undef QDEM_SETTING_MEMBER
};

}  // namespace qdem
