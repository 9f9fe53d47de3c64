// The compiled part of the qdem package: qdem._core.
#include <omp.h>
#include <pybind11/pybind11.h>

#include "core/Errors.hpp"
#include "core/Threads.hpp"

namespace py = pybind11;

void bindMesh(py::module_& m);
void bindWorld(py::module_& m);
void bindMesher(py::module_& m);
void bindRemesher(py::module_& m);
void bindSpheres(py::module_& m);
void bindChecks(py::module_& m);

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
    m.def("setThreads", [](int n) { qdem::qdemThreads() = n > 0 ? n : 0; }, py::arg("n"),
          "Number of OpenMP threads QDEM uses (0 = YADE's own, from yade -j).  YADE's setting is left "
          "alone: its force buffers are sized for its own thread count.");
    m.def("getThreads", []() { return qdem::effectiveThreads(); },
          "Number of OpenMP threads QDEM uses now.");
    bindMesh(m);
    bindWorld(m);
    bindChecks(m);  // (methods added to World)
    bindSpheres(m);
    bindMesher(m);
    bindRemesher(m);
}
