#include "SurfaceMesher.hpp"

#include "ShortFeatures.hpp"
#include "SizeGrid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <map>
#include <new>
#include <set>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
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

using FaceHandle = boost::graph_traits<Polyhedron>::face_descriptor;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Polyhedron>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using FacetVisitor = Criteria::Facet_criteria::Visitor;

// Local element size: `cap` everywhere, smaller in and near a part thinner
// than the cap (SizeGrid: graded away from the thin part's faces).
struct LocalSize {
    std::shared_ptr<const SizeGrid> grid;  // null: cap everywhere
    double cap = 0;
    double at(const Point& p) const { return grid ? std::min(cap, grid->at(p.x(), p.y(), p.z())) : cap; }
};

// LocalSize as a Mesh_3 sizing field (edges, facets, cells).
struct SizeField {
    LocalSize size;
    double operator()(const Point& p, int, const Domain::Index&) const { return size.at(p); }
};

// Mesh_3's facet-distance criterion (a surface triangle must lie within
// `distance` of the input surface), waived for triangles already smaller
// than `minFraction` x the local size.  Plain, it refines without bound
// where the input turns sharply without a protected feature (a scan's ear
// tip, a noisy bump): tets 40-180 x smaller than the rest set the stable
// step, to follow detail far below the element size.  (CGAL 6 names this
// facet_min_size; Mesh_3 5.5 has no such bound.)
class DistanceAboveMinSize : public CGAL::Mesh_3::Curvature_size_criterion<Tr, FacetVisitor> {
    using Base = CGAL::Mesh_3::Abstract_criterion<Tr, FacetVisitor>;
    using Quality = Base::Quality;
    using Is_bad = Base::Is_bad;

public:
    DistanceAboveMinSize(double distance, LocalSize minSize, double minFraction)
        : sqDistance_(distance * distance), minSize_(std::move(minSize)), minFraction_(minFraction) {}

protected:
    void do_accept(FacetVisitor& v) const override { v.visit(*this); }
    DistanceAboveMinSize* do_clone() const override { return new DistanceAboveMinSize(*this); }
    Is_bad do_is_bad(const Tr& tr, const Tr::Facet& f) const override {
        const auto& gt = tr.geom_traits();
        const Tr::Weighted_point& p1 = tr.point(f.first, (f.second + 1) & 3);
        const Tr::Weighted_point& p2 = tr.point(f.first, (f.second + 2) & 3);
        const Tr::Weighted_point& p3 = tr.point(f.first, (f.second + 3) & 3);
        const Point c = gt.construct_weighted_circumcenter_3_object()(p1, p2, p3);
        const Point& centre = f.first->get_facet_surface_center(f.second);
        const double sqDist = tr.min_squared_distance(c, centre);
        if (sqDist <= sqDistance_) return Is_bad();
        const double sqRadius = CGAL::squared_distance(c, gt.construct_point_3_object()(p1));
        const double small = minFraction_ * minSize_.at(centre);
        if (sqRadius < small * small) return Is_bad();
        return Is_bad(Quality(sqDistance_ / sqDist));
    }

private:
    double sqDistance_;
    LocalSize minSize_;
    double minFraction_;
};

// Dihedral angle below which an edge of the input is kept as a sharp feature.
constexpr double kFeatureAngleDeg = 60.0;
// Refuse requests that would plainly exhaust memory or take hours: the
// estimate below is about twice the real count, and CGAL needs about 0.45 kB
// and 70 us per tet (unit cube, cellSize 0.025: 276k tets, 120 MB, 20 s).
constexpr double kMaxEstimatedTets = 2.0e7;
// A part thinner than its cells comes out of Mesh_3 with its opposite faces
// merged (a non-manifold mesh).  Where the body is thinner than
// kThinBelow cells, the cells there are made this fraction of the
// thickness: three across.  Two across left tets spanning the part with
// their four nodes on its two sides, which neither perturbation nor
// exudation can reach: a bunny's ears 0.08 thick cut the step 9x below
// the median element, 4.1x with three across.
constexpr double kSizePerThickness = 1.0 / 3.0;
constexpr double kThinBelow = 2.0;
// How fast the element size may grow away from a thin part (size per unit
// length): neighbouring elements differ in size by about this fraction of
// their own size per element.
constexpr double kSizeGradation = 0.4;
// Two faces are opposite sides of a thin part when their outward normals
// are more than 120 degrees apart: the sides of an edge sharper than 60
// degrees (which Mesh_3 keeps as a feature) are not a thin part.
constexpr double kOppositeNormalsCos = -0.5;
// The facet-distance criterion is waived for surface triangles smaller
// than this fraction of the local surface size (see DistanceAboveMinSize).
constexpr double kDistanceWaivedBelow = 0.5;
// The default surface size and facet distance are reduced until the mesh
// keeps this fraction of the volume the surface encloses (at most
// kVolumePasses meshings).
constexpr double kVolumeKept = 0.99;
// Sliver perturbation's target smallest dihedral angle.  With the default (0,
// "as far as possible") and no time limit it runs without end on the
// slivers it cannot reach (those with four surface vertices): a bumpy ball's
// 2,900 tets took 70 s instead of 7 s, for a worst element 2.5 instead of 2.7
// x below the median (exudation, run to the end, does the rest).
constexpr double kPerturbUntilDeg = 5.0;
constexpr int kVolumePasses = 4;

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

// Parts of the body thinner than the cells: the thickness under each input
// face is the shortest distance, from points spread over the face (at most
// half a cell apart), along the inward normal to the first opposite face
// met.  Faces whose part needs cells smaller than `cap` are kept with that
// size, kSizePerThickness x thickness.
struct ThinParts {
    std::shared_ptr<const SizeGrid> grid;  // null: no thin part
    std::size_t faces = 0;                 // input faces on thin parts
    double thinnest = std::numeric_limits<double>::infinity();
    double estimatedTets = 0;  // tets the thin parts need, at their size
};

// The size field of the thin parts: each thin face's size on the grid nodes
// within one grid spacing of it, graded away from there (SizeGrid).  The
// grid resolves the smallest size with two spacings, or as finely as
// SizeGrid's node budget allows.
std::shared_ptr<const SizeGrid> gradedSizes(const Polyhedron& poly,
                                            const std::vector<std::pair<FaceHandle, double>>& thinFaces, double cap) {
    const CGAL::Bbox_3 box = CGAL::bbox_3(poly.points_begin(), poly.points_end());
    double smallest = cap;
    for (const auto& fs : thinFaces) smallest = std::min(smallest, fs.second);
    auto grid = std::make_shared<SizeGrid>(std::array<double, 3>{box.xmin(), box.ymin(), box.zmin()},
                                           std::array<double, 3>{box.xmax(), box.ymax(), box.zmax()},
                                           0.5 * smallest, cap);
    const double h = grid->spacing();
    for (const auto& [f, size] : thinFaces) {
        const auto e = f->halfedge();
        const K::Triangle_3 tri(e->vertex()->point(), e->next()->vertex()->point(),
                                e->next()->next()->vertex()->point());
        const CGAL::Bbox_3 b = tri.bbox();
        std::array<std::size_t, 3> first{}, last{};
        grid->range({b.xmin(), b.ymin(), b.zmin()}, {b.xmax(), b.ymax(), b.zmax()}, h, first, last);
        for (std::size_t i = first[0]; i <= last[0]; ++i)
            for (std::size_t j = first[1]; j <= last[1]; ++j)
                for (std::size_t k = first[2]; k <= last[2]; ++k) {
                    const auto x = grid->node(i, j, k);
                    if (CGAL::squared_distance(Point(x[0], x[1], x[2]), tri) <= h * h) grid->lower(i, j, k, size);
                }
    }
    grid->grade(kSizeGradation);
    return grid;
}

ThinParts findThinParts(const Polyhedron& poly, double cap) {
    ThinParts out;
    const AabbTree tree(faces(poly).first, faces(poly).second, poly);
    std::vector<std::pair<FaceHandle, double>> thinFaces;  // face, size there
    auto corners = [](FaceHandle f) {
        const auto h = f->halfedge();
        return std::array<Point, 3>{h->vertex()->point(), h->next()->vertex()->point(),
                                    h->next()->next()->vertex()->point()};
    };
    // The orientation orient_polygon_soup chose: outward when the signed
    // volume is positive.
    double vol6 = 0;
    const Point o = faces(poly).first != faces(poly).second ? corners(*faces(poly).first)[0] : CGAL::ORIGIN;
    for (FaceHandle f : faces(poly)) {
        const auto c = corners(f);
        vol6 += (c[0] - o) * CGAL::cross_product(c[1] - o, c[2] - o);
    }
    const double outward = vol6 >= 0 ? 1.0 : -1.0;
    auto unitNormal = [&](FaceHandle f) {
        const auto c = corners(f);
        const K::Vector_3 n = CGAL::cross_product(c[1] - c[0], c[2] - c[0]);
        return n * (outward / std::sqrt(n.squared_length()));
    };
    for (FaceHandle f : faces(poly)) {
        const auto c = corners(f);
        const K::Vector_3 n = unitNormal(f);
        const double longest = std::sqrt(std::max({CGAL::squared_distance(c[0], c[1]),
                                                   CGAL::squared_distance(c[1], c[2]),
                                                   CGAL::squared_distance(c[2], c[0])}));
        const int m = std::clamp(static_cast<int>(std::ceil(longest / (0.5 * cap))), 1, 24);
        std::vector<double> across;  // thickness at each sample (inf: no opposite face)
        auto probe = [&](double u, double v) {
            const Point q = c[0] + u * (c[1] - c[0]) + v * (c[2] - c[0]);
            const K::Ray_3 ray(q, -n);
            const auto hit = tree.first_intersection(ray, [f](FaceHandle g) { return g == f; });
            const Point* x = hit ? boost::get<Point>(&hit->first) : nullptr;
            across.push_back(!x || unitNormal(hit->second) * n > kOppositeNormalsCos
                                 ? std::numeric_limits<double>::infinity()
                                 : std::sqrt(CGAL::squared_distance(q, *x)));
        };
        // Centroids of the m^2 sub-triangles of an m-fold split of the face.
        for (int i = 0; i < m; ++i)
            for (int j = 0; i + j < m; ++j) {
                probe((i + 1.0 / 3) / m, (j + 1.0 / 3) / m);
                if (i + j + 2 <= m) probe((i + 2.0 / 3) / m, (j + 2.0 / 3) / m);
            }
        // The median over the face: a plate's faces are as thick everywhere,
        // a wedge's large face only near its tip, which Mesh_3 keeps as a
        // sharp feature (refining towards the tip would not end).
        std::nth_element(across.begin(), across.begin() + across.size() / 2, across.end());
        const double thickness = across[across.size() / 2];
        const double size = kSizePerThickness * thickness;
        if (thickness < kThinBelow * cap) {
            thinFaces.emplace_back(f, size);
            out.thinnest = std::min(out.thinnest, thickness);
            // The face's half of its part (area x thickness / 2) at that size
            // (the density of the estimate in meshClosedSurface).
            const double area = 0.5 * std::sqrt(CGAL::cross_product(c[1] - c[0], c[2] - c[0]).squared_length());
            out.estimatedTets += 4.0 * 0.5 * area * thickness / (0.513 * size * size * size);
        }
    }
    out.faces = thinFaces.size();
    if (!thinFaces.empty()) out.grid = gradedSizes(poly, thinFaces, cap);
    return out;
}

// Smallest height of tet t: 3 V / its largest face area.
double minHeight(const TetMesh& m, std::size_t t) {
    std::array<K::Vector_3, 4> x;
    for (int k = 0; k < 4; ++k) {
        const double* p = &m.nodes[3 * static_cast<std::size_t>(m.tets[4 * t + k])];
        x[k] = K::Vector_3(p[0], p[1], p[2]);
    }
    double largest = 0;
    for (int k = 0; k < 4; ++k) {
        const auto& a = x[(k + 1) % 4];
        const auto& b = x[(k + 2) % 4];
        const auto& c = x[(k + 3) % 4];
        largest = std::max(largest, CGAL::cross_product(b - a, c - a).squared_length());
    }
    return largest > 0 ? std::fabs(tetSixVolume(m, t)) / std::sqrt(largest) : 0.0;
}

// Boundary slivers: tets lying flat on the surface, two of their faces on
// it (outward normals within 45 degrees), four surface vertices.
// Perturbation and exudation cannot remove them (they keep the surface
// triangles); they set the stable step.  Those lower than the median
// element's height / kSliverHeightFactor go: the surface moves inward by
// their height, the volume by theirs.  A removal that would put an edge on
// four surface triangles (a non-manifold surface) is skipped.
constexpr double kSliverHeightFactor = 3.0;

std::size_t dropSurfaceSlivers(TetMesh& m) {
    std::size_t removed = 0;
    for (int round = 0; round < 8; ++round) {
        const std::size_t nt = m.nTets();
        if (nt < 2) break;
        std::vector<double> h(nt);
        for (std::size_t t = 0; t < nt; ++t) h[t] = minHeight(m, t);
        std::vector<double> sorted = h;
        std::nth_element(sorted.begin(), sorted.begin() + nt / 2, sorted.end());
        const double low = sorted[nt / 2] / kSliverHeightFactor;
        auto face = [&](std::size_t t, int k) {
            std::array<int32_t, 3> f{};
            int n = 0;
            for (int i = 0; i < 4; ++i)
                if (i != k) f[n++] = m.tets[4 * t + i];
            std::sort(f.begin(), f.end());
            return f;
        };
        std::map<std::array<int32_t, 3>, int> faceCount;
        for (std::size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 4; ++k) ++faceCount[face(t, k)];
        std::map<std::pair<int32_t, int32_t>, int> surfaceEdges;  // edge -> surface triangles on it
        for (const auto& [f, count] : faceCount)
            if (count == 1)
                for (int i = 0; i < 3; ++i)
                    ++surfaceEdges[{std::min(f[i], f[(i + 1) % 3]), std::max(f[i], f[(i + 1) % 3])}];
        auto point = [&](int32_t v) {
            const double* p = &m.nodes[3 * static_cast<std::size_t>(v)];
            return K::Vector_3(p[0], p[1], p[2]);
        };
        std::vector<char> drop(nt, 0);
        std::set<std::pair<int32_t, int32_t>> changed;  // opposite edges made surface this round
        bool any = false;
        for (std::size_t t = 0; t < nt; ++t) {
            if (h[t] >= low) continue;
            std::vector<int> out;
            for (int k = 0; k < 4; ++k)
                if (faceCount[face(t, k)] == 1) out.push_back(k);
            if (out.size() != 2) continue;
            // The surface faces are opposite vertices out[0], out[1]; the edge
            // they share joins the other two, the opposite edge joins these.
            const int32_t* c = &m.tets[4 * t];
            const int32_t a = c[out[0]], b = c[out[1]];
            const std::pair<int32_t, int32_t> opp{std::min(a, b), std::max(a, b)};
            if (surfaceEdges.count(opp) || changed.count(opp)) continue;
            // Outward normal of the face opposite vertex k: away from vertex k.
            auto normal = [&](int k) {
                std::array<int32_t, 3> f{};
                int n = 0;
                for (int i = 0; i < 4; ++i)
                    if (i != k) f[n++] = c[i];
                K::Vector_3 nv = CGAL::cross_product(point(f[1]) - point(f[0]), point(f[2]) - point(f[0]));
                if (nv * (point(c[k]) - point(f[0])) > 0) nv = -nv;
                return nv / std::sqrt(nv.squared_length());
            };
            if (normal(out[0]) * normal(out[1]) < std::sqrt(0.5)) continue;
            drop[t] = 1;
            changed.insert(opp);
            any = true;
        }
        if (!any) break;
        std::size_t kept = 0;
        for (std::size_t t = 0; t < nt; ++t) {
            if (drop[t]) {
                ++removed;
                continue;
            }
            for (int i = 0; i < 4; ++i) m.tets[4 * kept + i] = m.tets[4 * t + i];
            ++kept;
        }
        m.tets.resize(4 * kept);
    }
    return removed;
}

// Whether the boundary triangles of a tet mesh form a closed manifold surface.
bool surfaceIsManifold(const TetMesh& m) {
    std::map<std::array<int32_t, 3>, std::pair<int, std::array<int32_t, 3>>> faces;
    for (std::size_t t = 0; t < m.nTets(); ++t)
        for (int k = 0; k < 4; ++k) {
            std::array<int32_t, 3> f{};
            int n = 0;
            for (int i = 0; i < 4; ++i)
                if (i != k) f[n++] = m.tets[4 * t + i];
            std::array<int32_t, 3> key = f;
            std::sort(key.begin(), key.end());
            auto& e = faces[key];
            ++e.first;
            e.second = f;
        }
    std::vector<int32_t> tris;
    for (const auto& [key, e] : faces)
        if (e.first == 1) tris.insert(tris.end(), e.second.begin(), e.second.end());
    try {
        checkClosedManifold(tris, m.nNodes());
    } catch (const InputError&) {
        return false;
    }
    return true;
}

double meshVolume(const TetMesh& m) {
    double v6 = 0;
    for (std::size_t t = 0; t < m.nTets(); ++t) v6 += tetSixVolume(m, t);
    return v6 / 6.0;
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
                          double cellSize, double facetDistance, unsigned seed, double surfaceSize,
                          SurfaceMeshReport* report) {
    checkArguments(vertices, triangles, cellSize, facetDistance);
    if (std::isnan(surfaceSize) || std::isinf(surfaceSize))
        throw InputError(cat("meshClosedSurface: surfaceSize must be finite (<= 0 selects cellSize), got ", surfaceSize));
    double skin = surfaceSize > 0 ? surfaceSize : cellSize;
    double fd = facetDistance > 0 ? facetDistance : cellSize / 10.0;
    // The defaults are the caller's to override: only they adapt to the volume.
    const bool adapt = !(surfaceSize > 0) && !(facetDistance > 0);
    checkClosedManifold(triangles, vertices.size() / 3);
    Validated soup = buildSoup(vertices, triangles);

    TetMesh mesh;
    SurfaceMeshReport done;
    try {
        // Mesh_3 draws from CGAL's default generator (thread-local) and from
        // the domain's generator: both are seeded before every meshing, so
        // runs are reproducible.
        CGAL::Random rng(seed);

        Polyhedron poly = makePolyhedron(soup);
        if (!(soup.volume > 0))
            throw InputError("meshClosedSurface: the surface encloses no volume");
        // Sharp features shorter than a surface triangle: smoothed away
        // (ShortFeatures.hpp); kept as they are if that would make the
        // surface intersect itself.
        ShortFeatureReport shortFeatures;
        {
            std::vector<std::array<double, 3>> pts(soup.points.size());
            for (std::size_t i = 0; i < pts.size(); ++i)
                pts[i] = {soup.points[i].x(), soup.points[i].y(), soup.points[i].z()};
            shortFeatures = smoothShortFeatures(pts, soup.tris, kFeatureAngleDeg, skin);
            if (shortFeatures.smoothed > 0) {
                Validated smoothed = soup;
                for (std::size_t i = 0; i < pts.size(); ++i) smoothed.points[i] = Point(pts[i][0], pts[i][1], pts[i][2]);
                try {
                    poly = makePolyhedron(smoothed);
                    smoothed.volume = soup.volume;  // the volume kept is the user's surface's
                    smoothed.area = soup.area;
                    soup = std::move(smoothed);
                } catch (const InputError&) {
                    poly = makePolyhedron(soup);
                    shortFeatures.kept += shortFeatures.smoothed;
                    shortFeatures.smoothed = 0, shortFeatures.longestMoved = 0;
                }
            }
        }
        const ThinParts thin = findThinParts(poly, std::max(cellSize, skin));
        // A regular tet of circumradius R has volume 8 R^3 / (9 sqrt 3); four
        // times that density is about twice what Mesh_3 really produces.
        const double estimate = 4.0 * soup.volume / (0.513 * std::pow(std::min(cellSize, skin), 3)) +
                                thin.estimatedTets;
        if (estimate > kMaxEstimatedTets) {
            if (thin.estimatedTets > 0.5 * estimate)
                throw InputError(cat("meshClosedSurface: the body is too thin for ",
                                     surfaceSize > 0 ? "surfaceSize " : "cellSize ", skin, ": parts of it are ",
                                     thin.thinnest, " thick (measured through the body along the surface "
                                     "normals) and need tetrahedra of about ", kSizePerThickness * thin.thinnest,
                                     " there, about ", estimate, " tetrahedra in all (the limit is ",
                                     kMaxEstimatedTets, "). Thicken those parts, or mesh a plate as "
                                     "qdem.boxMesh with one or more cells across"));
            throw InputError(cat("meshClosedSurface: cellSize ", cellSize, " is too small for a body of volume ",
                                 soup.volume, " (about ", estimate, " tetrahedra; the limit is ",
                                 kMaxEstimatedTets, ")"));
        }

        Domain domain(poly, &rng);
        domain.detect_features(kFeatureAngleDeg);
        std::shared_ptr<const SizeGrid> thinSize = thin.grid;
        for (int pass = 1;; ++pass) {
            CGAL::get_default_random() = CGAL::Random(seed);
            rng = CGAL::Random(seed);
            const LocalSize cells{thinSize, cellSize};
            const LocalSize surface{thinSize, skin};
            Criteria criteria(Criteria::Edge_criteria(SizeField{surface}),
                              Criteria::Facet_criteria(25.0, SizeField{surface}, 0.0),
                              Criteria::Cell_criteria(3.0, SizeField{cells}));
            criteria.add_facet_criterion(new DistanceAboveMinSize(fd, surface, kDistanceWaivedBelow));
            // Time limits 0 = none: the default limits depend on the wall-clock
            // time of the refinement and would make the result non-deterministic.
            // Perturbation stops once every dihedral angle exceeds kPerturbUntilDeg;
            // exudation (sliver_bound 0) raises the smallest angle as far as it can.
            C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_lloyd(), P::no_odt(),
                                                P::perturb(P::time_limit = 0.0, P::sliver_bound = kPerturbUntilDeg),
                                                P::exude(P::time_limit = 0.0, P::sliver_bound = 0.0));
            mesh = extract(c3t3);
            // Mesh_3 leaves flat slivers on the flat faces of a plate thinner than
            // its cells (a 0.3 x 0.3 x 0.02 box at cellSize 0.015-0.04, found by a
            // tester): those in the surface go (the shape is the same).
            dropFlatSurfaceTets(mesh);
            {
                // Kept only if the surface stays closed and manifold (checked as
                // the input surface is); otherwise the slivers stay.
                TetMesh peeled = mesh;
                if (dropSurfaceSlivers(peeled) > 0 && surfaceIsManifold(peeled)) mesh = std::move(peeled);
            }
            // The thin-part sizing jumps from face to face; next to a sharp
            // wedge Mesh_3 can then merge faces (a concave dart prism): mesh
            // once more without it (the sizes asked, as everywhere else).
            if (thinSize && !surfaceIsManifold(mesh)) {
                thinSize.reset();
                --pass;
                continue;
            }
            done = SurfaceMeshReport{soup.volume, meshVolume(mesh), skin, fd, pass,
                                     !thinSize ? std::numeric_limits<double>::infinity() : thin.thinnest,
                                     thinSize ? thin.faces : 0, shortFeatures.smoothed, shortFeatures.longestMoved};
            const double lost = 1.0 - done.meshVolume / soup.volume;
            if (!adapt || lost <= 1.0 - kVolumeKept || pass == kVolumePasses || mesh.nTets() == 0) break;
            // The volume a surface triangle cuts off grows as its size squared
            // (its depth, size^2 / (2 x curvature radius), times its area) and as
            // the facet distance: aim at 0.7 % lost.
            const double ratio = std::max(0.1, 0.007 / lost);
            skin *= std::sqrt(ratio);
            fd *= ratio;
        }
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
    try {
        checkMesh(mesh);
    } catch (const InputError& e) {
        throw InputError(cat("meshClosedSurface: Mesh_3 produced a bad element (", e.what(), "). The body is about ",
                             2.0 * soup.volume / soup.area, " thick (2 x volume / surface area) against ",
                             surfaceSize > 0 ? "surfaceSize " : "cellSize ", skin,
                             ": use a smaller cellSize (and surfaceSize), or another seed; a plate meshes exactly "
                             "as qdem.boxMesh"));
    }
    if (report) *report = done;
    return mesh;
}

}  // namespace qdem
