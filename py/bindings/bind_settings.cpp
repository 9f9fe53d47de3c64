// The world's settings bound to Python from their one declaration
// (pkg/step/Settings.hpp): a checked property per setting on the core World,
// and qdem._core.settings(), the table QdemEngine builds its attributes from.
#include <cmath>
#include <sstream>
#include <type_traits>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "core/Errors.hpp"
#include "phases/ContactKind.hpp"
#include "world/World.hpp"

namespace py = pybind11;
using namespace qdem;

namespace {

// "must lie in [0, 1)", "must be > 0", "must be one of 0 ('spring'), 1 ('regularized')".
std::string describe(const SettingRange& r) {
    std::ostringstream s;
    if (!r.choices.empty()) {
        s << "must be one of";
        for (std::size_t i = 0; i < r.choices.size(); ++i) s << (i ? ", " : " ") << i << " ('" << r.choices[i] << "')";
    } else if (std::isfinite(r.lo) && std::isfinite(r.hi)) {
        s << "must lie in " << (r.loOpen ? "(" : "[") << r.lo << ", " << r.hi << (r.hiOpen ? ")" : "]");
    } else if (std::isfinite(r.lo)) {
        s << "must be " << (r.loOpen ? "> " : ">= ") << r.lo << " and finite";
    } else {
        s << "must be finite";
    }
    if (!r.note.empty()) s << ": " << r.note;
    return s.str();
}

bool allowed(const SettingRange& r, double v) {
    if (!r.choices.empty()) return v == std::floor(v) && v >= 0 && v < static_cast<double>(r.choices.size());
    if (!std::isfinite(v)) return false;
    if (r.loOpen ? !(v > r.lo) : !(v >= r.lo)) return false;
    return r.hiOpen ? v < r.hi : v <= r.hi;
}

// Python value <-> member: bools as bool, enums as their int value (the
// engine shows the choice names), numbers as float.
template <class T>
py::object toPython(const T& v) {
    if constexpr (std::is_enum_v<T>) return py::int_(static_cast<int>(v));
    else return py::cast(v);
}

template <class T>
void assign(T& member, const py::object& value, const char* name, const SettingRange& range) {
    if constexpr (std::is_same_v<T, bool>) {
        member = py::cast<bool>(value);
    } else {
        double v;
        try {
            v = py::cast<double>(value);
        } catch (const py::cast_error&) {
            throw InputError("World." + std::string(name) + "=" + py::cast<std::string>(py::repr(value)) + " is invalid: " +
                             describe(range));
        }
        const bool integral = std::is_integral_v<T> && !std::is_same_v<T, bool>;
        if (!allowed(range, v) || (integral && v != std::floor(v)))
            throw InputError("World." + std::string(name) + "=" + py::cast<std::string>(py::repr(value)) + " is invalid: " +
                             (integral ? "must be a whole number, " : "") + describe(range));
        member = static_cast<T>(v);
    }
}

// Is b the member a points at (only bool members can be switches)?
template <class T>
bool sameMember(bool Settings::*a, T Settings::*b) {
    if constexpr (std::is_same_v<T, bool>) return a == b;
    else return false;
}

}  // namespace

void bindSettings(py::module_& m, py::class_<World>& world) {
    py::list table;
#define QDEM_BIND_SETTING(T, name, engineName, def, range, doc)                                                    \
    {                                                                                                              \
        const SettingRange r = range;                                                                              \
        world.def_property(                                                                                        \
            #name, [](const World& w) { return toPython(w.settings.name); },                                      \
            [r](World& w, const py::object& v) { assign(w.settings.name, v, #name, r); },                          \
            (std::string(doc) + " (" + describe(r) + ")").c_str());                                                \
        py::dict d;                                                                                                \
        d["name"] = #name;                                                                                         \
        d["engineName"] = engineName;                                                                              \
        d["default"] = toPython(static_cast<T>(def));                                                              \
        d["doc"] = doc;                                                                                            \
        d["kind"] = std::is_same_v<T, bool> ? "bool"                                                               \
                    : std::is_enum_v<T>     ? "choice"                                                             \
                    : std::is_integral_v<T> ? "integer"                                                            \
                                            : "real";                                                              \
        d["lo"] = r.lo, d["hi"] = r.hi, d["loOpen"] = r.loOpen, d["hiOpen"] = r.hiOpen;                            \
        d["choices"] = r.choices;                                                                                  \
        d["rule"] = describe(r);                                                                                   \
        table.append(d);                                                                                           \
    }
    QDEM_SETTINGS(QDEM_BIND_SETTING)
#undef QDEM_BIND_SETTING
    m.attr("settings") = table;

    // The contact-kinds table (pkg/phases/ContactKind.hpp), each row with the
    // name of the setting that switches it (its engine attribute: settings).
    py::list kinds;
    for (const ContactKindRow& row : contactKinds()) {
        py::dict d;
        d["name"] = row.name;
        d["registers"] = row.registers;
        d["history"] = row.history;
        py::object sw = py::none();
#define QDEM_SWITCH_NAME(T, name, engineName, def, range, doc) \
    if (sameMember(row.on, &Settings::name)) sw = py::str(#name);
        QDEM_SETTINGS(QDEM_SWITCH_NAME)
#undef QDEM_SWITCH_NAME
        d["switch"] = sw;
        kinds.append(d);
    }
    m.attr("contactKinds") = kinds;
}
