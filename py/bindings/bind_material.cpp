// Materials bound to Python from their one declaration (pkg/material/Material.hpp):
// the tables qdem._core.materialFields and materialLaws that QdemMat builds its
// attributes from, the check each QdemMat attribute goes through
// (checkMaterialValue: the core's rule and message), and the keyword
// World.addMaterial.
#include <string>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "core/Errors.hpp"
#include "material/Material.hpp"
#include "world/World.hpp"

namespace py = pybind11;
using namespace qdem;

namespace {

const MaterialField* findField(const std::string& name) {
    for (const MaterialField& f : kMaterialFields)
        if (name == f.name) return &f;
    return nullptr;
}

std::string knownNames() {
    std::string s;
    for (const MaterialField& f : kMaterialFields) s += std::string(f.name) + ", ";
    return s + "law";
}

std::string shown(const py::handle& v) { return py::cast<std::string>(py::repr(v)); }

// A real number as Python scripts write one (int, float, NumPy scalars); not a
// bool (True would be E = 1 Pa), a string (float('1e6') would pass), a
// complex number or an array.
bool isRealNumber(const py::handle& v) {
    if (py::isinstance<py::bool_>(v) || py::isinstance(v, py::module_::import("numpy").attr("bool_"))) return false;
    return py::isinstance(v, py::module_::import("numbers").attr("Real"));
}

double checkedNumber(const MaterialField& f, const py::handle& v) {
    if (isRealNumber(v)) {
        const double x = py::cast<double>(py::float_(py::reinterpret_borrow<py::object>(v)));
        if (f.range.allows(x)) return x;
    }
    throw InputError(invalidMaterialValue(f.name, shown(v), f.range.rule()));
}

MaterialLaw checkedLaw(const py::handle& v) {
    MaterialLaw law{};
    if (!py::isinstance<py::str>(v) || !lawFromName(py::cast<std::string>(v), law))
        throw InputError(invalidMaterialValue("law", shown(v), lawRule()));
    return law;
}

}  // namespace

void bindMaterial(py::module_& m, py::class_<World>& world) {
    py::list fields;
    for (const MaterialField& f : kMaterialFields) {
        py::dict d;
        d["name"] = f.name;
        d["default"] = f.def;
        d["unit"] = f.unit;
        d["doc"] = f.doc;
        d["kind"] = "real";
        d["lo"] = f.range.lo, d["hi"] = f.range.hi, d["loOpen"] = f.range.loOpen, d["hiOpen"] = f.range.hiOpen;
        d["rule"] = f.range.rule();
        fields.append(d);
    }
    m.attr("materialFields") = fields;

    py::list laws;  // in declaration order; the first is the default
#define QDEM_LAW_ROW(Tag, name, doc)                          \
    {                                                         \
        py::dict d;                                           \
        d["name"] = name;                                     \
        d["tag"] = #Tag;                                      \
        d["value"] = static_cast<int>(MaterialLaw::Tag);      \
        d["doc"] = doc;                                       \
        laws.append(d);                                       \
    }
    QDEM_MATERIAL_LAWS(QDEM_LAW_ROW)
#undef QDEM_LAW_ROW
    m.attr("materialLaws") = laws;

    m.def(
        "checkMaterialValue",
        [](const std::string& name, const py::object& value) -> py::object {
            if (name == "law") return py::str(lawName(checkedLaw(value)));
            const MaterialField* f = findField(name);
            if (!f) throw py::type_error("QdemMat: no parameter " + name + "; known: " + knownNames());
            return py::float_(checkedNumber(*f, value));
        },
        py::arg("name"), py::arg("value"),
        "The value of material parameter 'name' as the core keeps it (a float, or the law's name), or "
        "ValueError naming the parameter, the value and what it must be (pkg/material/Material.hpp).");

    world.def(
        "addMaterial",
        [](World& w, const py::kwargs& kw) {
            Material mat;
            for (const auto& item : kw) {
                const std::string name = py::cast<std::string>(item.first);
                if (name == "law") {
                    mat.law = checkedLaw(item.second);
                    continue;
                }
                const MaterialField* f = findField(name);
                if (!f) throw py::type_error("addMaterial: unknown keyword '" + name + "'; known: " + knownNames());
                mat.*(f->member) = checkedNumber(*f, item.second);
            }
            return w.addMaterial(mat);
        },
        "Add a material from keyword parameters (those of qdem._core.materialFields and law, a law's name; "
        "the others keep their defaults); returns its index.");
}
