// The compiled part of the qdem package: qdem._core.
#include <omp.h>
#include <pybind11/pybind11.h>

#include "core/Errors.hpp"

namespace py = pybind11;

void bindMesh(py::module_& m);
void bindWorld(py::module_& m);
void bindMesher(py::module_& m);
void bindSpheres(py::module_& m);

PYBIND11_MODULE(_core, m) {
    m.doc() = "yade-qdem compiled core: QDEM world, meshes, contacts";
    static py::exception<qdem::StabilityError> stability(m, "StabilityError", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const qdem::InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const qdem::StabilityError& e) {
            stability(e.what());
        }
    });
    m.def("setThreads", [](int n) { omp_set_num_threads(n > 0 ? n : 1); }, py::arg("n"),
          "Number of OpenMP threads QDEM uses.");
    m.def("getThreads", []() { return omp_get_max_threads(); });
    bindMesh(m);
    bindWorld(m);
    bindSpheres(m);
    bindMesher(m);
}
