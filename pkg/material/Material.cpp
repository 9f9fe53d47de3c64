#include "Material.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

namespace {
// "1e+06", "0.4": six significant digits, as the rest of the messages.
std::string shown(double v) { return cat(v); }
}  // namespace

std::string MaterialRange::rule() const {
    auto num = [](double x) { return shown(x); };
    if (std::isfinite(lo) && std::isfinite(hi))
        return cat("must be a number in ", loOpen ? "(" : "[", num(lo), ", ", num(hi), hiOpen ? ")" : "]");
    if (std::isfinite(lo)) return cat("must be a number ", loOpen ? "> " : ">= ", num(lo));
    if (std::isfinite(hi)) return cat("must be a number ", hiOpen ? "< " : "<= ", num(hi));
    return "must be a finite number";
}

std::string invalidMaterialValue(const char* name, const std::string& value, const std::string& rule) {
    return cat("QdemMat: ", name, "=", value, " is invalid: ", rule);
}

void Material::validate() const {
    for (const MaterialField& f : kMaterialFields)
        if (!f.range.allows(this->*f.member))
            throw InputError(invalidMaterialValue(f.name, shown(this->*f.member), f.range.rule()));
    for (MaterialLaw l : kMaterialLaws)
        if (law == l) return;
    throw InputError(invalidMaterialValue("law", shown(static_cast<int>(law)), lawRule()));
}

const char* lawName(MaterialLaw law) {
    switch (law) {
#define QDEM_LAW_NAME(Tag, name, doc) \
    case MaterialLaw::Tag: return name;
        QDEM_MATERIAL_LAWS(QDEM_LAW_NAME)
#undef QDEM_LAW_NAME
    }
    return "unknown";
}

bool lawFromName(const std::string& name, MaterialLaw& law) {
    for (MaterialLaw l : kMaterialLaws)
        if (name == lawName(l)) {
            law = l;
            return true;
        }
    return false;
}

std::string lawRule() {
    std::string s = "must be one of";
    for (MaterialLaw l : kMaterialLaws) s += cat(l == kMaterialLaws[0] ? " '" : ", '", lawName(l), "'");
    return s;
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
