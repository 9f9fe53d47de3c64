#include "SurfaceMesher.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <new>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_polyhedron_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/exceptions.h>
#include <CGAL/make_mesh_3.h>
#include <boost/iterator/function_output_iterator.hpp>

namespace qdem {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Polyhedron = CGAL::Mesh_polyhedron_3<K>::type;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K, Polyhedron>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace P = CGAL::parameters;

// Dihedral angle below which an edge of the input is kept as a sharp feature.
constexpr double kFeatureAngleDeg = 60.0;
// Refuse requests that would plainly exhaust memory or take hours: the
// estimate below is about twice the real count, and CGAL needs about 0.45 kB
// and 70 us per tet (unit cube, cellSize 0.025: 276k tets, 120 MB, 20 s).
constexpr double kMaxEstimatedTets = 2.0e7;
// A body thinner than about 0.4 surface cells comes out of Mesh_3 with its
// opposite faces merged (a non-manifold mesh, after minutes for a large
// plate): refused at once below this fraction of the surface cell size.  The
// thickness is estimated as 2 x volume / area (a plate's thickness; half a
// rod's diameter; a third of a cube's side).
constexpr double kMinThicknessPerCell = 0.2;

struct Validated {
    std::vector<Point> points;                     // used vertices only
    std::vector<int32_t> inputIndex;               // input index of each point
    std::vector<std::array<std::size_t, 3>> tris;  // into points, input order
    double volume = 0;                             // enclosed volume (absolute)
    double area = 0;                               // surface area
    double extent = 0;                             // largest side of the bounding box
};

void checkArguments(const std::vector<double>& vertices, const std::vector<int32_t>& triangles, double cellSize,
                    double facetDistance) {
    if (vertices.size() % 3 != 0)
        throw InputError(cat("meshClosedSurface: vertex array length ", vertices.size(), " is not a multiple of 3"));
    if (triangles.size() % 3 != 0)
        throw InputError(
            cat("meshClosedSurface: triangle array length ", triangles.size(), " is not a multiple of 3"));
    const std::size_t nv = vertices.size() / 3, nt = triangles.size() / 3;
    if (nv < 4) throw InputError(cat("meshClosedSurface: a closed surface needs at least 4 vertices, got ", nv));
    if (nt < 4) throw InputError(cat("meshClosedSurface: a closed surface needs at least 4 triangles, got ", nt));
    if (nv > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
        throw InputError(cat("meshClosedSurface: too many vertices (", nv, ")"));
    if (!std::isfinite(cellSize) || cellSize <= 0)
        throw InputError(cat("meshClosedSurface: cellSize must be finite and > 0, got ", cellSize));
    if (std::isnan(facetDistance) || std::isinf(facetDistance))
        throw InputError(
            cat("meshClosedSurface: facetDistance must be finite (<= 0 selects cellSize/10), got ", facetDistance));
    for (std::size_t i = 0; i < vertices.size(); ++i)
        if (!std::isfinite(vertices[i]))
            throw InputError(cat("meshClosedSurface: vertex ", i / 3, " has a NaN or infinite coordinate"));
    for (std::size_t t = 0; t < nt; ++t) {
        const int32_t* c = &triangles[3 * t];
        for (int k = 0; k < 3; ++k) {
            if (c[k] < 0 || static_cast<std::size_t>(c[k]) >= nv)
                throw InputError(cat("meshClosedSurface: triangle ", t, " refers to vertex ", c[k],
                                     " but there are only ", nv, " vertices"));
            for (int j = 0; j < k; ++j)
                if (c[j] == c[k])
                    throw InputError(cat("meshClosedSurface: triangle ", t, " repeats vertex ", c[k],
                                         " (degenerate triangle)"));
        }
    }
}

// Every undirected edge must belong to exactly two triangles, and the
// triangles around each vertex must form a single fan.
void checkClosedManifold(const std::vector<int32_t>& triangles, std::size_t nv) {
    const std::size_t nt = triangles.size() / 3;
    struct EdgeUse {
        uint64_t key;
        uint32_t tri;
    };
    std::vector<EdgeUse> uses;
    uses.reserve(3 * nt);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint64_t a = static_cast<uint32_t>(triangles[3 * t + k]);
            const uint64_t b = static_cast<uint32_t>(triangles[3 * t + (k + 1) % 3]);
            uses.push_back({std::min(a, b) << 32 | std::max(a, b), static_cast<uint32_t>(t)});
        }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
        return x.key < y.key || (x.key == y.key && x.tri < y.tri);
    });

    // Union-find over triangle corners (3 t + k): two triangles sharing the
    // edge (a, b) are neighbours in the fan around a and in the fan around b.
    std::vector<uint32_t> parent(3 * nt);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    auto corner = [&](uint32_t t, uint32_t v) {
        for (uint32_t k = 0; k < 3; ++k)
            if (static_cast<uint32_t>(triangles[3 * t + k]) == v) return 3 * t + k;
        return 3 * t;  // unreachable: v is a vertex of t
    };

    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i;
        while (j < uses.size() && uses[j].key == uses[i].key) ++j;
        const std::size_t count = j - i;
        const uint32_t a = static_cast<uint32_t>(uses[i].key >> 32), b = static_cast<uint32_t>(uses[i].key);
        if (count == 1)
            throw InputError(cat("meshClosedSurface: the surface is not closed: edge (", a, ", ", b,
                                 ") belongs only to triangle ", uses[i].tri,
                                 " (each edge of a closed manifold surface must belong to exactly 2 "
                                 "triangles; are there holes or unmerged duplicate vertices?)"));
        if (count > 2)
            throw InputError(cat("meshClosedSurface: the surface is not manifold: edge (", a, ", ", b,
                                 ") belongs to ", count, " triangles (", uses[i].tri, ", ", uses[i + 1].tri, ", ",
                                 uses[i + 2].tri, count > 3 ? ", ..." : "",
                                 "); each edge must belong to exactly 2 triangles"));
        const uint32_t t1 = uses[i].tri, t2 = uses[i + 1].tri;
        if (t1 == t2)
            throw InputError(cat("meshClosedSurface: triangle ", t1, " uses edge (", a, ", ", b, ") twice"));
        for (uint32_t v : {a, b}) {
            const uint32_t r1 = find(corner(t1, v)), r2 = find(corner(t2, v));
            if (r1 != r2) parent[r1] = r2;
        }
        i = j;
    }

    std::vector<int64_t> fanRoot(nv, -1);
    for (std::size_t c = 0; c < 3 * nt; ++c) {
        const uint32_t v = static_cast<uint32_t>(triangles[c]);
        const int64_t r = find(static_cast<uint32_t>(c));
        if (fanRoot[v] < 0)
            fanRoot[v] = r;
        else if (fanRoot[v] != r)
            throw InputError(cat("meshClosedSurface: the surface is not manifold at vertex ", v,
                                 ": separate fans of triangles meet there (e.g. two bodies touching at a point)"));
    }
}

Validated buildSoup(const std::vector<double>& vertices, const std::vector<int32_t>& triangles) {
    const std::size_t nv = vertices.size() / 3, nt = triangles.size() / 3;
    Validated s;
    std::vector<int64_t> newIndex(nv, -1);
    s.tris.resize(nt);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const int32_t v = triangles[3 * t + k];
            if (newIndex[v] < 0) {
                newIndex[v] = static_cast<int64_t>(s.points.size());
                s.points.emplace_back(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]);
                s.inputIndex.push_back(v);
            }
            s.tris[t][k] = static_cast<std::size_t>(newIndex[v]);
        }
    for (std::size_t t = 0; t < nt; ++t) {
        const auto& c = s.tris[t];
        if (CGAL::collinear(s.points[c[0]], s.points[c[1]], s.points[c[2]]))
            throw InputError(cat("meshClosedSurface: triangle ", t, " (vertices ", triangles[3 * t], ", ",
                                 triangles[3 * t + 1], ", ", triangles[3 * t + 2],
                                 ") is degenerate: its vertices are coincident or collinear"));
    }
    return s;
}

Polyhedron makePolyhedron(Validated& s) {
    if (!PMP::orient_polygon_soup(s.points, s.tris))
        throw InputError(
            "meshClosedSurface: the triangles cannot be consistently oriented (non-manifold or non-orientable "
            "surface); CGAL cannot turn this polygon soup into a polyhedron");
    if (!PMP::is_polygon_soup_a_polygon_mesh(s.tris))
        throw InputError(
            "meshClosedSurface: CGAL cannot turn this triangle soup into a polyhedron (inconsistent "
            "orientation or non-manifold vertices)");
    Polyhedron poly;
    PMP::polygon_soup_to_polygon_mesh(s.points, s.tris, poly);
    if (poly.size_of_facets() != s.tris.size() || !poly.is_closed() || !poly.is_pure_triangle())
        throw InputError("meshClosedSurface: CGAL could not build a closed triangulated polyhedron from the surface");

    // Polyhedron_3 keeps faces in insertion order: face i is triangle i.
    std::unordered_map<const void*, std::size_t> faceIndex;
    {
        std::size_t i = 0;
        for (auto f = poly.facets_begin(); f != poly.facets_end(); ++f) faceIndex[&*f] = i++;
    }
    std::size_t nIntersecting = 0;
    std::pair<std::size_t, std::size_t> first{0, 0};
    PMP::self_intersections(poly, boost::make_function_output_iterator([&](const auto& fp) {
                                if (nIntersecting++ == 0)
                                    first = {faceIndex.at(&*fp.first), faceIndex.at(&*fp.second)};
                            }));
    if (nIntersecting)
        throw InputError(cat("meshClosedSurface: the surface intersects itself (", nIntersecting,
                             " pairs of intersecting triangles, e.g. triangles ", std::min(first.first, first.second),
                             " and ", std::max(first.first, first.second), ")"));

    // Divergence theorem, relative to the bounding-box centre to avoid
    // cancellation when the body lies far from the origin.
    const CGAL::Bbox_3 box = CGAL::bbox_3(s.points.begin(), s.points.end());
    const K::Vector_3 o((box.xmin() + box.xmax()) / 2, (box.ymin() + box.ymax()) / 2, (box.zmin() + box.zmax()) / 2);
    double vol6 = 0;
    for (const auto& c : s.tris) {
        const K::Vector_3 a = s.points[c[0]] - CGAL::ORIGIN - o, b = s.points[c[1]] - CGAL::ORIGIN - o,
                          d = s.points[c[2]] - CGAL::ORIGIN - o;
        vol6 += a * CGAL::cross_product(b, d);
    }
    s.volume = std::fabs(vol6) / 6.0;
    s.area = 0;
    for (const auto& c : s.tris)
        s.area += std::sqrt(CGAL::cross_product(s.points[c[1]] - s.points[c[0]], s.points[c[2]] - s.points[c[0]])
                                .squared_length()) /
                  2.0;
    s.extent = std::max({box.xmax() - box.xmin(), box.ymax() - box.ymin(), box.zmax() - box.zmin()});
    return poly;
}

TetMesh extract(const C3t3& c3t3) {
    TetMesh m;
    std::unordered_map<Tr::Vertex_handle, int32_t> index;
    for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
        std::array<int32_t, 4> ids{};
        for (int k = 0; k < 4; ++k) {
            const Tr::Vertex_handle v = c->vertex(k);
            auto it = index.find(v);
            if (it == index.end()) {
                if (index.size() >= static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
                    throw InputError("meshClosedSurface: the mesh has too many nodes for 32-bit indices");
                it = index.emplace(v, static_cast<int32_t>(index.size())).first;
                const auto& p = v->point();
                m.nodes.push_back(CGAL::to_double(p.x()));
                m.nodes.push_back(CGAL::to_double(p.y()));
                m.nodes.push_back(CGAL::to_double(p.z()));
            }
            ids[k] = it->second;
        }
        m.tets.insert(m.tets.end(), ids.begin(), ids.end());
    }
    for (std::size_t t = 0; t < m.nTets(); ++t)
        if (tetSixVolume(m, t) < 0) std::swap(m.tets[4 * t + 2], m.tets[4 * t + 3]);
    return m;
}

}  // namespace

TetMesh meshClosedSurface(const std::vector<double>& vertices, const std::vector<int32_t>& triangles,
                          double cellSize, double facetDistance, unsigned seed, double surfaceSize) {
    checkArguments(vertices, triangles, cellSize, facetDistance);
    if (std::isnan(surfaceSize) || std::isinf(surfaceSize))
        throw InputError(cat("meshClosedSurface: surfaceSize must be finite (<= 0 selects cellSize), got ", surfaceSize));
    const double skin = surfaceSize > 0 ? surfaceSize : cellSize;
    checkClosedManifold(triangles, vertices.size() / 3);
    Validated soup = buildSoup(vertices, triangles);

    TetMesh mesh;
    try {
        // Mesh_3 draws from CGAL's default generator (thread-local) and from
        // the domain's generator: seed both so runs are reproducible.
        CGAL::get_default_random() = CGAL::Random(seed);
        CGAL::Random rng(seed);

        Polyhedron poly = makePolyhedron(soup);
        if (!(soup.volume > 0))
            throw InputError("meshClosedSurface: the surface encloses no volume");
        const double thickness = 2.0 * soup.volume / soup.area;
        if (thickness < kMinThicknessPerCell * skin && soup.extent > skin)
            throw InputError(cat("meshClosedSurface: the body is too thin for ",
                                 surfaceSize > 0 ? "surfaceSize " : "cellSize ", skin, ": it is about ", thickness,
                                 " thick (2 x volume / surface area), and tetrahedra of that size cannot fit "
                                 "between its opposite faces (Mesh_3 would merge them into a non-manifold mesh). "
                                 "Use a cellSize (and surfaceSize) of at most about 2 x the thickness, here <= ",
                                 2.0 * thickness, ", or mesh a plate as qdem.boxMesh with one or more cells across"));
        // A regular tet of circumradius R has volume 8 R^3 / (9 sqrt 3); four
        // times that density is about twice what Mesh_3 really produces.
        const double estimate = 4.0 * soup.volume / (0.513 * std::pow(std::min(cellSize, skin), 3));
        if (estimate > kMaxEstimatedTets)
            throw InputError(cat("meshClosedSurface: cellSize ", cellSize, " is too small for a body of volume ",
                                 soup.volume, " (about ", estimate, " tetrahedra; the limit is ",
                                 kMaxEstimatedTets, ")"));

        const double fd = facetDistance > 0 ? facetDistance : cellSize / 10.0;
        Domain domain(poly, &rng);
        domain.detect_features(kFeatureAngleDeg);
        Criteria criteria(P::edge_size = skin, P::facet_angle = 25.0, P::facet_size = skin,
                          P::facet_distance = fd, P::cell_radius_edge_ratio = 3.0, P::cell_size = cellSize);
        // Time limits 0 = none: the default limits depend on the wall-clock
        // time of the refinement and would make the result non-deterministic.
        C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_lloyd(), P::no_odt(),
                                            P::perturb(P::time_limit = 0.0), P::exude(P::time_limit = 0.0));
        mesh = extract(c3t3);
    } catch (const InputError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(cat("meshClosedSurface: CGAL failed to mesh the surface: ", e.what()));
    }

    if (mesh.nTets() == 0)
        throw InputError(cat("meshClosedSurface: the mesh has no tetrahedra (cellSize ", cellSize,
                             " may be too large for a body of volume ", soup.volume, ")"));
    // Mesh_3 leaves flat slivers on the flat faces of a plate thinner than
    // its cells (a 0.3 x 0.3 x 0.02 box at cellSize 0.015-0.04, found by a
    // tester): those in the surface go (the shape is the same), any other
    // is named with the remedy rather than as a tetrahedron number alone.
    dropFlatSurfaceTets(mesh);
    try {
        checkMesh(mesh);
    } catch (const InputError& e) {
        throw InputError(cat("meshClosedSurface: Mesh_3 produced a bad element (", e.what(), "). The body is about ",
                             2.0 * soup.volume / soup.area, " thick (2 x volume / surface area) against ",
                             surfaceSize > 0 ? "surfaceSize " : "cellSize ", skin,
                             ": use a smaller cellSize (and surfaceSize), or another seed; a plate meshes exactly "
                             "as qdem.boxMesh"));
    }
    return mesh;
}

}  // namespace qdem
