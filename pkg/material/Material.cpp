#include "Material.hpp"

#include <cmath>
#include <limits>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

void Material::validate() const {
    auto bad = [](const char* name, double v, const char* rule) {
        throw InputError(cat("QdemMat: ", name, "=", v, " is invalid: ", rule));
    };
    if (!std::isfinite(young) || young <= 0) bad("young", young, "must be > 0");
    if (!std::isfinite(poisson) || poisson >= 0.5 || poisson <= -1)
        bad("poisson", poisson, "must lie in (-1, 0.5)");
    if (!std::isfinite(density) || density <= 0) bad("density", density, "must be > 0");
    if (!std::isfinite(viscosity) || viscosity < 0) bad("viscosity", viscosity, "must be >= 0");
    if (!std::isfinite(frictionPiece) || frictionPiece < 0) bad("frictionPiece", frictionPiece, "must be >= 0");
    if (!std::isfinite(frictionWall) || frictionWall < 0) bad("frictionWall", frictionWall, "must be >= 0");
    if (!std::isfinite(radius) || radius <= 0) bad("radius", radius, "must be > 0");
    if (!std::isfinite(restitution) || restitution <= 0 || restitution > 1)
        bad("restitution", restitution, "must lie in (0, 1]");
    if (law != MaterialLaw::StableNeoHookean && law != MaterialLaw::SaintVenantKirchhoff)
        throw InputError(cat("QdemMat: law=", static_cast<int>(law),
                             " is invalid: must be 0 (stableNeoHookean) or 1 (saintVenantKirchhoff)"));
}

const char* lawName(MaterialLaw law) {
    switch (law) {
        case MaterialLaw::StableNeoHookean: return "stableNeoHookean";
        case MaterialLaw::SaintVenantKirchhoff: return "saintVenantKirchhoff";
    }
    return "unknown";
}

double dampingRatioFromRestitution(double e) {
    if (e >= 1) return 0.0;
    const double l = std::log(e);
    return -l / std::sqrt(M_PI * M_PI + l * l);
}

double leapfrogLimit(double omega, double xi) {
    // A NaN frequency or damping (a material at the edge of the doubles: density
    // 1e-300, viscosity 1e300) must refuse every step, never pass as "no limit".
    if (std::isnan(omega) || std::isnan(xi)) return 0.0;
    if (omega <= 0) return std::numeric_limits<double>::infinity();
    if (std::isinf(omega) || std::isinf(xi)) return xi == -std::numeric_limits<double>::infinity() && !std::isinf(omega)
                                                          ? std::numeric_limits<double>::infinity() : 0.0;
    if (xi < 1e3) return 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
    // sqrt(1 + xi^2) - xi cancels (and xi^2 overflows past 1e154): the same number as 1 / (hypot(1, xi) + xi).
    return 2.0 / omega / (std::hypot(1.0, xi) + xi);
}

}  // namespace qdem
