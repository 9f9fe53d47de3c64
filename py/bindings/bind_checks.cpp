// The periodic checks and the stable step's version (PeriodicChecks.cpp,
// StableStepVersion.cpp), added to the World class bind_world.cpp made.
#include <pybind11/pybind11.h>

#include "world/World.hpp"

namespace py = pybind11;
using namespace qdem;

void bindChecks(py::module_& m) {
    auto world = py::reinterpret_borrow<py::class_<World>>(m.attr("World"));
    world
        .def(
            "periodicChecks",
            [](World& w, long checkPeriod, long gatherPeriod, double dt, bool checkDt) -> py::object {
                const PeriodicChecks r = w.periodicChecks(checkPeriod, gatherPeriod, dt, checkDt);
                if (!r.ran) return py::none();
                py::dict inv, edges, d;
                inv["count"] = r.inverted.count;
                inv["piece"] = r.inverted.piece;
                inv["element"] = r.inverted.element;
                inv["volumeRatio"] = r.inverted.volumeRatio;
                edges["count"] = r.edges.count;
                edges["obstacle"] = r.edges.obstacle;
                edges["bodyId"] = r.edges.bodyId;
                edges["piece"] = r.edges.piece;
                edges["point"] = py::make_tuple(r.edges.point[0], r.edges.point[1], r.edges.point[2]);
                d["inverted"] = inv;
                d["edges"] = edges;
                return d;
            },
            py::arg("checkPeriod"), py::arg("gatherPeriod"), py::arg("dt"), py::arg("checkDt"),
            "The checks due at this step (core.iter a multiple of checkPeriod; 0: never), in one call: inverted "
            "elements, dt against the current shape (with checkDt), finite state, deep piece overlap, YADE spheres "
            "inside pieces, obstacle edges through surfaces; under MPI every node gathered first, and every "
            "gatherPeriod steps.  Raises StabilityError as the checks do; returns None when none was due, else "
            "{'inverted': checkInverted's dict, 'edges': obstacleEdgeCrossing's dict}.")
        .def_property_readonly(
            "stableStepVersion", &World::stableStepVersion,
            "A number that changes whenever something the stable step depends on has changed: any setting, a "
            "piece or material added, the obstacles or the YADE spheres set.  A check of O.dt cached under "
            "(O.dt, stableStepVersion) is redone exactly when its answer could differ.");
}
