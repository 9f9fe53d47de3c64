// Mesh utilities: structured boxes, checks, surfaces, Hilbert order.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "Arrays.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Components.hpp"
#include "mesh/Hilbert.hpp"
#include "mesh/Surface.hpp"
#include "mesh/TetMesh.hpp"

namespace py = pybind11;
using namespace qdem;
using qdem::py_::flatten;

namespace {

using Nodes = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Tets = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;

TetMesh toMesh(const Nodes& nodes, const Tets& tets) {
    TetMesh m;
    m.nodes = flatten<double>(nodes, 3, "nodes");
    m.tets = flatten<int32_t>(tets, 4, "tets");
    return m;
}

using qdem::py_::toArray;

py::tuple meshTuple(const TetMesh& m) { return py::make_tuple(toArray(m.nodes, 3), toArray(m.tets, 4)); }

}  // namespace

void bindMesh(py::module_& m) {
    m.def(
        "boxMesh",
        [](int nx, int ny, int nz, double lx, double ly, double lz, int tetsPerCell) {
            return meshTuple(boxMesh(nx, ny, nz, lx, ly, lz, tetsPerCell));
        },
        py::arg("nx"), py::arg("ny"), py::arg("nz"), py::arg("lx"), py::arg("ly"), py::arg("lz"),
        py::arg("tetsPerCell") = 6, "Structured box mesh centred on the origin: returns (nodes (N,3), tets (T,4)).");
    m.def(
        "checkMesh", [](const Nodes& n, const Tets& t) { checkMesh(toMesh(n, t)); }, py::arg("nodes"),
        py::arg("tets"), "Raise ValueError naming the first defect (NaN, bad index, inverted or zero-volume tet).");
    m.def(
        "meshParts",
        [](const Nodes& n, const Tets& t) {
            const MeshParts p = meshParts(toMesh(n, t));
            return toArray(p.tetPart, 1).reshape({-1});
        },
        py::arg("nodes"), py::arg("tets"),
        "Part of each tet (tets sharing a node are in one part; parts numbered by their first tet).");
    m.def(
        "orientPositive",
        [](const Nodes& n, const Tets& t) {
            TetMesh mesh = toMesh(n, t);
            const std::size_t flipped = orientPositive(mesh);
            return py::make_tuple(toArray(mesh.tets, 4), flipped);
        },
        py::arg("nodes"), py::arg("tets"), "Flip negatively oriented tets: returns (tets, number flipped).");
    m.def(
        "tetVolumes",
        [](const Nodes& n, const Tets& t) {
            TetMesh mesh = toMesh(n, t);
            py::array_t<double> v(static_cast<py::ssize_t>(mesh.nTets()));
            for (std::size_t e = 0; e < mesh.nTets(); ++e) v.mutable_at(e) = tetSixVolume(mesh, e) / 6.0;
            return v;
        },
        py::arg("nodes"), py::arg("tets"), "Signed volume of each tetrahedron.");
    m.def(
        "extractSurface",
        [](const Nodes& n, const Tets& t) {
            const Surface s = extractSurface(toMesh(n, t));
            py::dict d;
            d["triangles"] = toArray(s.triangles, 3);
            d["triTet"] = toArray(s.triTet, 1).reshape({-1});
            d["edges"] = toArray(s.edges, 2);
            d["nodes"] = toArray(s.nodes, 1).reshape({-1});
            d["tets"] = toArray(s.tets, 1).reshape({-1});
            return d;
        },
        py::arg("nodes"), py::arg("tets"),
        "Boundary of a positively oriented mesh: dict of triangles (outward), triTet, edges, nodes, tets.");
    m.def(
        "hilbertReorder",
        [](const Nodes& n, const Tets& t, bool tetOrder) {
            TetMesh mesh = toMesh(n, t);
            std::vector<int32_t> tetOldOf;
            const std::vector<int32_t> oldOf = hilbertReorder(mesh, &tetOldOf);
            if (tetOrder)
                return py::make_tuple(toArray(mesh.nodes, 3), toArray(mesh.tets, 4), toArray(oldOf, 1).reshape({-1}),
                                      toArray(tetOldOf, 1).reshape({-1}));
            return py::make_tuple(toArray(mesh.nodes, 3), toArray(mesh.tets, 4),
                                  toArray(oldOf, 1).reshape({-1}));
        },
        py::arg("nodes"), py::arg("tets"), py::arg("tetOrder") = false,
        "Reorder along a Hilbert curve: returns (nodes, tets, oldIndexOfNewNode), and oldIndexOfNewTet "
        "with tetOrder=True.");
}
