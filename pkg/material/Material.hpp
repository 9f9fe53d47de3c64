// QDEM material: Kelvin-Voigt viscoelastic solid plus the contact parameters
// of its surface particles.  Defaults are the seed paper's Table 1.
//
// Its parameters and its elastic laws are declared once, here, in the two
// lists below.  From them come the members of Material, validate() and its
// messages, lawName, the law dispatch (pkg/element/MaterialLaw.hpp), the
// keyword World.addMaterial and the tables qdem._core.materialFields /
// materialLaws (py/bindings/bind_material.cpp), from which the Python QdemMat
// builds its attributes, defaults, docstrings and checks (py/qdem/material.py),
// and the list of laws the tests run over (tests/cpp/test_laws.cpp).
// Adding a parameter is one line of QDEM_MATERIAL_FIELDS (and the code that
// uses it); adding a law is its file in pkg/element/laws/, one line of
// QDEM_MATERIAL_LAWS and its #include in MaterialLaw.hpp.
#pragma once
#include <cmath>
#include <string>

namespace qdem {

// The values a material parameter may take: a finite number in an interval
// with open or closed ends (an infinite end is open).
struct MaterialRange {
    double lo = -INFINITY, hi = INFINITY;
    bool loOpen = true, hiOpen = true;
    static constexpr MaterialRange above(double lo) { return {lo, INFINITY, true, true}; }
    static constexpr MaterialRange atLeast(double lo) { return {lo, INFINITY, false, true}; }
    static constexpr MaterialRange between(double lo, double hi, bool loOpen, bool hiOpen) {
        return {lo, hi, loOpen, hiOpen};
    }
    bool allows(double v) const {
        return std::isfinite(v) && (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
    }
    // What a value must be: "must be a number > 0", "must be a number in (-1, 0.5)".
    std::string rule() const;
};

// X(type, member, default, unit ("" if none), range, doc)
#define QDEM_MATERIAL_FIELDS(X)                                                                                      \
    X(double, young, 5.0e8, "Pa", MaterialRange::above(0), "Young's modulus E.")                                    \
    X(double, poisson, 0.4, "", MaterialRange::between(-1, 0.5, true, true), "Poisson's ratio nu.")                 \
    X(double, density, 700.0, "kg/m^3", MaterialRange::above(0), "Mass density rho.")                               \
    X(double, viscosity, 2.5e5, "Pa s", MaterialRange::atLeast(0),                                                   \
      "Shear viscosity eta of the Kelvin-Voigt dashpot; the viscous stress is (eta/mu) times the elastic stress "    \
      "of the strain rate (doc/formulation.md). 0 = purely elastic.")                                               \
    X(double, frictionPiece, 0.1, "", MaterialRange::atLeast(0),                                                     \
      "Coulomb kinetic friction coefficient against other QDEM pieces.")                                            \
    X(double, frictionWall, 0.5, "", MaterialRange::atLeast(0),                                                      \
      "Coulomb kinetic friction coefficient against YADE walls, boxes and facets (the smaller of it and "           \
      "tan(frictionAngle) of the body's material acts, as in YADE).")                                              \
    X(double, radius, 0.04, "m", MaterialRange::above(0),                                                            \
      "Radius of the surface particles: contacts start when a node comes within this distance of a wall (2x of "   \
      "another piece's surface). Sets the contact stiffness kn = 2 E r (rigid wall).")                              \
    X(double, restitution, 0.5, "", MaterialRange::between(0, 1, true, false),                                       \
      "Normal restitution coefficient of one particle contact; sets the contact dashpot.")

// Elastic laws of the elements (pkg/element/laws/<Tag>.hpp, doc/formulation.md
// "Material laws"); all equal Hooke's law with (young, poisson) at small
// strain.  The first is the default.  X(Tag = law class, Python name, doc)
#define QDEM_MATERIAL_LAWS(X)                                                                                        \
    X(StableNeoHookean, "stableNeoHookean",                                                                          \
      "Smith, de Goes and Kim 2018: resists compression without softening and pushes an inverted element back.")     \
    X(SaintVenantKirchhoff, "saintVenantKirchhoff",                                                                  \
      "the seed paper's law; its compression response peaks at stretch 1/sqrt(3) and an element crushed past it "   \
      "can stay inverted (QdemEngine then stops with an error).")

enum class MaterialLaw : int {
#define QDEM_LAW_ENUM(Tag, name, doc) Tag,
    QDEM_MATERIAL_LAWS(QDEM_LAW_ENUM)
#undef QDEM_LAW_ENUM
};

// Every law, in declaration order.
inline constexpr MaterialLaw kMaterialLaws[] = {
#define QDEM_LAW_ITEM(Tag, name, doc) MaterialLaw::Tag,
    QDEM_MATERIAL_LAWS(QDEM_LAW_ITEM)
#undef QDEM_LAW_ITEM
};

// The Python name of a law ("stableNeoHookean", "saintVenantKirchhoff").
const char* lawName(MaterialLaw law);
// The law with that Python name; false if none has it.
bool lawFromName(const std::string& name, MaterialLaw& law);
// What a law must be: "must be one of 'stableNeoHookean', 'saintVenantKirchhoff'".
std::string lawRule();

struct Material {
#define QDEM_MATERIAL_MEMBER(T, name, def, unit, range, doc) T name = def;
    QDEM_MATERIAL_FIELDS(QDEM_MATERIAL_MEMBER)
#undef QDEM_MATERIAL_MEMBER
    MaterialLaw law = kMaterialLaws[0];

    double lambda() const { return young * poisson / ((1 + poisson) * (1 - 2 * poisson)); }
    double mu() const { return young / (2 * (1 + poisson)); }
    // Viscous stress = beta * (elastic stress of the strain rate): the shear
    // viscosity is eta = beta*mu and the bulk follows Poisson's ratio.
    double beta() const { return viscosity / mu(); }
    double pWaveModulus() const { return lambda() + 2 * mu(); }

    // Throws InputError naming the offending parameter, its value and what it must be.
    void validate() const;
};

// One row of QDEM_MATERIAL_FIELDS, for code that goes over all of them.
struct MaterialField {
    const char* name;
    double Material::*member;
    double def;
    const char* unit;
    MaterialRange range;
    const char* doc;
};

inline constexpr MaterialField kMaterialFields[] = {
#define QDEM_MATERIAL_ROW(T, name, def, unit, range, doc) {#name, &Material::name, def, unit, range, doc},
    QDEM_MATERIAL_FIELDS(QDEM_MATERIAL_ROW)
#undef QDEM_MATERIAL_ROW
};

// "QdemMat: young=-1 is invalid: must be a number > 0" (value as the caller shows it).
std::string invalidMaterialValue(const char* name, const std::string& shown, const std::string& rule);

// Normal damping ratio of a spring-dashpot with restitution e in (0, 1].
double dampingRatioFromRestitution(double e);

// Central-difference (leapfrog) stability limit of one mode with angular
// frequency omega and damping ratio xi, the velocity lagging half a step:
// dt <= 2/omega * (sqrt(1 + xi^2) - xi).  See doc/formulation.md.
double leapfrogLimit(double omega, double xi);

}  // namespace qdem
