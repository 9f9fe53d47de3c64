// QDEM material: Kelvin-Voigt viscoelastic solid plus the contact parameters
// of its surface particles.  Defaults are the seed paper's Table 1.
#pragma once

namespace qdem {

// Elastic law of the elements (pkg/element/laws/, doc/formulation.md "Material
// laws").  Both equal Hooke's law with (young, poisson) at small strain.
enum class MaterialLaw : int {
    StableNeoHookean = 0,      // Smith, de Goes, Kim 2018: restoring for any F, inversion included
    SaintVenantKirchhoff = 1,  // softens past stretch 1/sqrt(3) and can stay inverted
};
// The Python name of a law ("stableNeoHookean", "saintVenantKirchhoff").
const char* lawName(MaterialLaw law);

struct Material {
    double young = 5.0e8;        // Young's modulus E [Pa]
    double poisson = 0.4;        // Poisson's ratio nu
    double density = 700.0;      // rho [kg/m^3]
    double viscosity = 2.5e5;    // shear viscosity eta [Pa s] (Kelvin-Voigt)
    double frictionPiece = 0.1;  // kinetic friction against other pieces
    double frictionWall = 0.5;   // kinetic friction against walls, boxes, facets
    double radius = 0.04;        // radius r of the surface particles [m]
    double restitution = 0.5;    // normal restitution of one particle contact
    MaterialLaw law = MaterialLaw::StableNeoHookean;

    double lambda() const { return young * poisson / ((1 + poisson) * (1 - 2 * poisson)); }
    double mu() const { return young / (2 * (1 + poisson)); }
    // Viscous stress = beta * (elastic stress of the strain rate): the shear
    // viscosity is eta = beta*mu and the bulk follows Poisson's ratio.
    double beta() const { return viscosity / mu(); }
    double pWaveModulus() const { return lambda() + 2 * mu(); }

    // Throws InputError naming the offending parameter.
    void validate() const;
};

// Normal damping ratio of a spring-dashpot with restitution e in (0, 1].
double dampingRatioFromRestitution(double e);

// Central-difference (leapfrog) stability limit of one mode with angular
// frequency omega and damping ratio xi, the velocity lagging half a step:
// dt <= 2/omega * (sqrt(1 + xi^2) - xi).  See doc/formulation.md.
double leapfrogLimit(double omega, double xi);

}  // namespace qdem
