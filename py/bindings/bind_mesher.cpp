// CGAL Mesh_3 binding: tetrahedral meshing of closed triangle surfaces.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <stdexcept>

#ifdef QDEM_HAVE_CGAL
#include "Arrays.hpp"
#include "mesh/SurfaceMesher.hpp"
#include "mesh/TetMesh.hpp"
#endif

namespace py = pybind11;

namespace {

constexpr const char* kDoc =
    "meshClosedSurface(vertices, triangles, cellSize, facetDistance=-1.0, seed=0, surfaceSize=-1.0)\n\n"
    "Fill a closed, manifold, non-self-intersecting triangle surface with tetrahedra (CGAL Mesh_3).\n"
    "vertices (V,3) float64, triangles (F,3) int32 (any orientation); cellSize bounds the tet\n"
    "circumradius and the surface triangle size; facetDistance bounds the distance to the input\n"
    "surface (<= 0: cellSize/10); surfaceSize bounds surface triangles alone (<= 0: cellSize).  Sharp edges (< 60 deg) are kept,\n"
    "except sets of them shorter than the surface size, smoothed away first.  Equal inputs and seed give\n"
    "identical meshes.  Parts thinner than the cells get cells of half their thickness; with the default\n"
    "surfaceSize and facetDistance the surface is refined until the mesh keeps 99 % of the volume.\n"
    "Returns (nodes (N,3) float64, tets (T,4) int32, report dict: surfaceVolume, meshVolume,\n"
    "surfaceSize, facetDistance, passes, thinnest, thinFaces, shortFeatures, shortFeatureMove), tets\n"
    "positively oriented.\n"
    "Raises ValueError naming the problem for invalid input.";

using qdem::py_::toArray;

}  // namespace

void bindMesher(py::module_& m) {
#ifdef QDEM_HAVE_CGAL
    using Vertices = py::array_t<double, py::array::c_style | py::array::forcecast>;
    using Triangles = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;
    m.attr("haveCgal") = true;
    m.def(
        "meshClosedSurface",
        [](const Vertices& vertices, const Triangles& triangles, double cellSize, double facetDistance,
           unsigned seed, double surfaceSize) {
            const std::vector<double> v = qdem::py_::flatten<double>(vertices, 3, "vertices");
            const std::vector<int32_t> t = qdem::py_::flatten<int32_t>(triangles, 3, "triangles");
            qdem::TetMesh mesh;
            qdem::SurfaceMeshReport r;
            {
                py::gil_scoped_release release;
                mesh = qdem::meshClosedSurface(v, t, cellSize, facetDistance, seed, surfaceSize, &r);
            }
            py::dict report;
            report["surfaceVolume"] = r.surfaceVolume;
            report["meshVolume"] = r.meshVolume;
            report["surfaceSize"] = r.surfaceSize;
            report["facetDistance"] = r.facetDistance;
            report["passes"] = r.passes;
            report["thinnest"] = r.thinnest;
            report["thinFaces"] = r.thinFaces;
            report["shortFeatures"] = r.shortFeatures;
            report["shortFeatureMove"] = r.shortFeatureMove;
            return py::make_tuple(toArray(mesh.nodes, 3), toArray(mesh.tets, 4), report);
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("cellSize"), py::arg("facetDistance") = -1.0,
        py::arg("seed") = 0u, py::arg("surfaceSize") = -1.0, kDoc);
#else
    m.attr("haveCgal") = false;
    m.def(
        "meshClosedSurface",
        [](const py::object&, const py::object&, double, double, unsigned, double) -> py::tuple {
            throw std::runtime_error("qdem was built without CGAL: install libcgal-dev and rebuild");
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("cellSize"), py::arg("facetDistance") = -1.0,
        py::arg("seed") = 0u, py::arg("surfaceSize") = -1.0, kDoc);
#endif
}
