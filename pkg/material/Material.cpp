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
    if (omega <= 0) return std::numeric_limits<double>::infinity();
    return 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
}

}  // namespace qdem
