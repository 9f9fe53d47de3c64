// CGAL tetrahedral remeshing binding: sliver removal from an existing mesh.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <stdexcept>

#ifdef QDEM_HAVE_CGAL
#include "Arrays.hpp"
#include "mesh/TetMesh.hpp"
#include "mesh/TetRemesher.hpp"
#endif

namespace py = pybind11;

namespace {

constexpr const char* kRemeshDoc =
    "remeshTets(nodes, tets, targetEdge=-1.0, iterations=8, featureAngle=40.0)\n\n"
    "Remesh a tetrahedral mesh to a uniform edge length with CGAL's tetrahedral isotropic remeshing,\n"
    "keeping its boundary surface (vertices move on it), feature edges (outward normals turning by more\n"
    "than featureAngle degrees) and corners.  targetEdge <= 0: the median boundary edge.  While the worst\n"
    "element cuts the step by more than 2.5x against the median one, up to 3 more rounds of 3 passes.\n"
    "Returns a dict: nodes (N,3), tets (T,4), featureEdges (E,2) and corners (C,) in the input's node\n"
    "indices (unused nodes dropped first), patches, projected, rounds, targetEdge, maxDeviation, maxDeviationOut,\n"
    "maxDeviationIn (sampled surface distances).  Raises ValueError naming the problem.";

constexpr const char* kFeatureDoc =
    "boundaryFeatureEdges(nodes, tets, featureAngle=40.0)\n\n"
    "Boundary edges (E,2), a < b, where the outward normals of the two boundary triangles turn by more\n"
    "than featureAngle degrees.";

using qdem::py_::toArray;

}  // namespace

void bindRemesher(py::module_& m) {
#ifdef QDEM_HAVE_CGAL
    using Nodes = py::array_t<double, py::array::c_style | py::array::forcecast>;
    using Tets = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;
    m.def(
        "remeshTets",
        [](const Nodes& nodes, const Tets& tets, double targetEdge, int iterations, double featureAngle) {
            qdem::TetMesh in;
            in.nodes = qdem::py_::flatten<double>(nodes, 3, "nodes");
            in.tets = qdem::py_::flatten<int32_t>(tets, 4, "tets");
            qdem::RemeshOptions opt;
            opt.targetEdge = targetEdge;
            opt.iterations = iterations;
            opt.featureAngleDeg = featureAngle;
            qdem::RemeshResult r;
            {
                py::gil_scoped_release release;
                r = qdem::remeshTets(in, opt);
            }
            py::dict d;
            d["nodes"] = toArray(r.mesh.nodes, 3);
            d["tets"] = toArray(r.mesh.tets, 4);
            d["featureEdges"] = toArray(r.featureEdges, 2);
            d["corners"] = toArray(r.corners, 1).attr("ravel")();
            d["patches"] = r.patches;
            d["projected"] = r.projected;
            d["rounds"] = r.rounds;
            d["targetEdge"] = r.targetEdge;
            d["maxDeviation"] = r.maxDeviation;
            d["maxDeviationOut"] = r.maxDeviationOut;
            d["maxDeviationIn"] = r.maxDeviationIn;
            return d;
        },
        py::arg("nodes"), py::arg("tets"), py::arg("targetEdge") = -1.0, py::arg("iterations") = 8,
        py::arg("featureAngle") = 40.0, kRemeshDoc);
    m.def(
        "boundaryFeatureEdges",
        [](const Nodes& nodes, const Tets& tets, double featureAngle) {
            qdem::TetMesh in;
            in.nodes = qdem::py_::flatten<double>(nodes, 3, "nodes");
            in.tets = qdem::py_::flatten<int32_t>(tets, 4, "tets");
            return toArray(qdem::boundaryFeatureEdges(in, featureAngle), 2);
        },
        py::arg("nodes"), py::arg("tets"), py::arg("featureAngle") = 40.0, kFeatureDoc);
#else
    m.def(
        "remeshTets",
        [](const py::object&, const py::object&, double, int, double) -> py::dict {
            throw std::runtime_error("qdem was built without CGAL: install libcgal-dev and rebuild");
        },
        py::arg("nodes"), py::arg("tets"), py::arg("targetEdge") = -1.0, py::arg("iterations") = 8,
        py::arg("featureAngle") = 40.0, kRemeshDoc);
    m.def(
        "boundaryFeatureEdges",
        [](const py::object&, const py::object&, double) -> py::object {
            throw std::runtime_error("qdem was built without CGAL: install libcgal-dev and rebuild");
        },
        py::arg("nodes"), py::arg("tets"), py::arg("featureAngle") = 40.0, kFeatureDoc);
#endif
}
