#include "TetRemesher.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "Surface.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_3/tet_soup_to_c3t3.h>
#include <CGAL/Tetrahedral_remeshing/Remeshing_triangulation_3.h>
#include <CGAL/tetrahedral_remeshing.h>

namespace qdem {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Vec = K::Vector_3;
using Tr = CGAL::Tetrahedral_remeshing::Remeshing_triangulation_3<K>;
using Vh = Tr::Vertex_handle;
using Triangle = K::Triangle_3;
using TriIt = std::vector<Triangle>::const_iterator;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_triangle_primitive<K, TriIt>>>;

// The remesher's edge_is_constrained_map: a writable set of vertex pairs
// (ordered as CGAL orders them), shared by the copies CGAL makes of it.
struct ConstrainedEdges {
    using key_type = std::pair<Vh, Vh>;
    using value_type = bool;
    using reference = bool;
    using category = boost::read_write_property_map_tag;
    std::shared_ptr<std::set<key_type>> edges = std::make_shared<std::set<key_type>>();

    friend bool get(const ConstrainedEdges& m, const key_type& k) { return m.edges->count(k) > 0; }
    friend void put(const ConstrainedEdges& m, const key_type& k, bool v) {
        if (v)
            m.edges->insert(k);
        else
            m.edges->erase(k);
    }
};

std::pair<Vh, Vh> orderedPair(Vh a, Vh b) { return b < a ? std::make_pair(b, a) : std::make_pair(a, b); }

Point point(const TetMesh& m, std::size_t i) { return {m.nodes[3 * i], m.nodes[3 * i + 1], m.nodes[3 * i + 2]}; }

// The mesh without the nodes no tet uses (CGAL's triangulation would hold
// them as isolated vertices).
TetMesh compact(const TetMesh& in) {
    std::vector<int32_t> index(in.nNodes(), -1);
    TetMesh out;
    out.tets.reserve(in.tets.size());
    for (int32_t v : in.tets) {
        if (index[v] < 0) {
            index[v] = static_cast<int32_t>(out.nNodes());
            out.nodes.insert(out.nodes.end(), in.nodes.begin() + 3 * v, in.nodes.begin() + 3 * v + 3);
        }
        out.tets.push_back(index[v]);
    }
    return out;
}

uint64_t edgeKey(int32_t a, int32_t b) {
    const uint64_t lo = static_cast<uint32_t>(std::min(a, b)), hi = static_cast<uint32_t>(std::max(a, b));
    return lo << 32 | hi;
}

Vec triangleNormal(const TetMesh& m, const int32_t* tri) {
    const Point a = point(m, tri[0]), b = point(m, tri[1]), c = point(m, tri[2]);
    return CGAL::cross_product(b - a, c - a);
}

// Height of tet t over its largest face, against its longest edge: 0 for a
// flat tet, 0.816 for the regular one.
double flatness(const TetMesh& m, std::size_t t) {
    const int32_t* c = &m.tets[4 * t];
    std::array<Point, 4> p;
    for (int k = 0; k < 4; ++k) p[k] = point(m, c[k]);
    double maxArea2 = 0, maxEdge2 = 0;
    for (int k = 0; k < 4; ++k) {
        const Point &a = p[(k + 1) % 4], &b = p[(k + 2) % 4], &d = p[(k + 3) % 4];
        maxArea2 = std::max(maxArea2, CGAL::cross_product(b - a, d - a).squared_length());
        for (int j = k + 1; j < 4; ++j) maxEdge2 = std::max(maxEdge2, CGAL::squared_distance(p[k], p[j]));
    }
    const double six = std::fabs(tetSixVolume(m, t));
    // height = 3 V / area = 6 V / (2 area) = six / |cross|
    return maxArea2 > 0 && maxEdge2 > 0 ? six / std::sqrt(maxArea2) / std::sqrt(maxEdge2) : 0.0;
}

std::vector<int32_t> featureEdgesOf(const TetMesh& m, const Surface& s, double featureAngleDeg) {
    // The two boundary triangles of every boundary edge.
    std::unordered_map<uint64_t, std::array<int32_t, 2>> faces;
    faces.reserve(s.edges.size());
    for (std::size_t f = 0; f < s.nTriangles(); ++f)
        for (int k = 0; k < 3; ++k) {
            auto [it, fresh] = faces.try_emplace(edgeKey(s.triangles[3 * f + k], s.triangles[3 * f + (k + 1) % 3]),
                                                 std::array<int32_t, 2>{static_cast<int32_t>(f), -1});
            if (!fresh) it->second[1] = static_cast<int32_t>(f);
        }
    const double cosMax = std::cos(featureAngleDeg * M_PI / 180.0);
    std::vector<int32_t> out;
    for (std::size_t e = 0; e < s.nEdges(); ++e) {
        const auto& f = faces.at(edgeKey(s.edges[2 * e], s.edges[2 * e + 1]));
        if (f[1] < 0) continue;
        const Vec n1 = triangleNormal(m, &s.triangles[3 * f[0]]), n2 = triangleNormal(m, &s.triangles[3 * f[1]]);
        const double c = n1 * n2 / std::sqrt(n1.squared_length() * n2.squared_length());
        if (c < cosMax) {
            out.push_back(s.edges[2 * e]);
            out.push_back(s.edges[2 * e + 1]);
        }
    }
    return out;
}

// Surface patches: boundary triangles connected across non-feature edges
// share a patch (numbered from 1).  CGAL fits one smooth surface per patch
// and projects the moved boundary vertices onto it, and it keeps every edge
// between two patches as a feature: a box's faces stay flat, its edges sharp.
std::map<std::array<int, 3>, int> surfacePatches(const Surface& s, const std::vector<int32_t>& features,
                                                 std::size_t* nPatches) {
    std::unordered_map<uint64_t, int> isFeature;
    for (std::size_t e = 0; e < features.size() / 2; ++e) isFeature[edgeKey(features[2 * e], features[2 * e + 1])] = 1;
    std::unordered_map<uint64_t, std::vector<int32_t>> edgeFaces;
    for (std::size_t f = 0; f < s.nTriangles(); ++f)
        for (int k = 0; k < 3; ++k)
            edgeFaces[edgeKey(s.triangles[3 * f + k], s.triangles[3 * f + (k + 1) % 3])].push_back(
                static_cast<int32_t>(f));
    std::vector<int> patch(s.nTriangles(), 0);
    int next = 0;
    std::vector<int32_t> stack;
    for (std::size_t seed = 0; seed < s.nTriangles(); ++seed) {
        if (patch[seed]) continue;
        patch[seed] = ++next;
        stack.assign(1, static_cast<int32_t>(seed));
        while (!stack.empty()) {
            const int32_t f = stack.back();
            stack.pop_back();
            for (int k = 0; k < 3; ++k) {
                const uint64_t key = edgeKey(s.triangles[3 * f + k], s.triangles[3 * f + (k + 1) % 3]);
                if (isFeature.count(key)) continue;
                for (int32_t g : edgeFaces[key])
                    if (!patch[g]) {
                        patch[g] = next;
                        stack.push_back(g);
                    }
            }
        }
    }
    *nPatches = static_cast<std::size_t>(next);
    // Keyed as CGAL's tet-soup loader looks facets up: the smallest index
    // first, in either orientation.
    std::map<std::array<int, 3>, int> out;
    for (std::size_t f = 0; f < s.nTriangles(); ++f) {
        std::array<int, 3> t{s.triangles[3 * f], s.triangles[3 * f + 1], s.triangles[3 * f + 2]};
        std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
        out[t] = patch[f];
    }
    return out;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
}

std::vector<Triangle> surfaceTriangles(const TetMesh& m, const Surface& s) {
    std::vector<Triangle> tris;
    tris.reserve(s.nTriangles());
    for (std::size_t f = 0; f < s.nTriangles(); ++f)
        tris.emplace_back(point(m, s.triangles[3 * f]), point(m, s.triangles[3 * f + 1]),
                          point(m, s.triangles[3 * f + 2]));
    return tris;
}

// Largest distance from the vertices and face centres of surface `from` to
// the triangles of `to`.
double sampledDistance(const std::vector<Triangle>& from, const std::vector<Triangle>& to) {
    AabbTree tree(to.begin(), to.end());
    tree.accelerate_distance_queries();
    double d2 = 0;
    for (const Triangle& t : from) {
        for (int k = 0; k < 3; ++k) d2 = std::max(d2, tree.squared_distance(t.vertex(k)));
        d2 = std::max(d2, tree.squared_distance(CGAL::centroid(t)));
    }
    return std::sqrt(d2);
}

// Full passes of each extra round of remeshing.
constexpr int kExtraIterations = 3;

// median(h_e) / min(h_e) over the cells of the body, h_e = (sum_a 1/H_a^2)^(-1/2)
// with H_a the height over the face opposite vertex a: the factor by which
// the worst element cuts the elastic step against the median one
// (qdem.remesh.elementSizes explains h_e).
double stepFactor(const Tr& tr) {
    std::vector<double> he;
    for (auto c : tr.finite_cell_handles()) {
        if (c->subdomain_index() == 0) continue;
        const Point &p0 = c->vertex(0)->point(), &p1 = c->vertex(1)->point(), &p2 = c->vertex(2)->point(),
                    &p3 = c->vertex(3)->point();
        const double six = std::fabs(CGAL::cross_product(p1 - p0, p2 - p0) * (p3 - p0));
        const std::array<Point, 4> p{p0, p1, p2, p3};
        double s = 0;
        for (int k = 0; k < 4; ++k) {
            const Point &a = p[(k + 1) % 4], &b = p[(k + 2) % 4], &d = p[(k + 3) % 4];
            s += CGAL::cross_product(b - a, d - a).squared_length() / (six * six);
        }
        he.push_back(s > 0 && std::isfinite(s) ? 1.0 / std::sqrt(s) : 0.0);
    }
    if (he.empty()) return 1.0;
    const double lo = *std::min_element(he.begin(), he.end());
    return lo > 0 ? median(he) / lo : std::numeric_limits<double>::infinity();
}

// The cells of the body; dimension[i] is CGAL's in_dimension of node i (0
// corner, 1 on a feature edge, 2 on the surface, 3 inside).
TetMesh extract(const Tr& tr, std::vector<int>& dimension) {
    TetMesh m;
    dimension.clear();
    std::unordered_map<Vh, int32_t> index;
    for (auto c : tr.finite_cell_handles()) {
        if (c->subdomain_index() == 0) continue;
        std::array<int32_t, 4> ids{};
        for (int k = 0; k < 4; ++k) {
            const Vh v = c->vertex(k);
            auto it = index.find(v);
            if (it == index.end()) {
                if (index.size() >= static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
                    throw InputError("improveMesh: the remeshed mesh has too many nodes for 32-bit indices");
                it = index.emplace(v, static_cast<int32_t>(index.size())).first;
                const Point& p = v->point();
                m.nodes.push_back(p.x());
                m.nodes.push_back(p.y());
                m.nodes.push_back(p.z());
                dimension.push_back(v->in_dimension());
            }
            ids[k] = it->second;
        }
        m.tets.insert(m.tets.end(), ids.begin(), ids.end());
    }
    for (std::size_t t = 0; t < m.nTets(); ++t)
        if (tetSixVolume(m, t) < 0) std::swap(m.tets[4 * t + 2], m.tets[4 * t + 3]);
    return m;
}

// Moves the surface nodes (dimension 2) onto the closest point of the input
// surface.  CGAL projects them onto a moving-least-squares fit of it, which
// on a coarsely faceted curved surface lies inside it (a 32-gon cylinder
// lost 1 % of its volume).  A move that would flatten or invert a tet (its
// flatness below half of what it was) is undone.  Returns the number moved.
std::size_t projectOntoInput(TetMesh& m, const std::vector<int>& dimension, const std::vector<Triangle>& input) {
    AabbTree tree(input.begin(), input.end());
    tree.accelerate_distance_queries();
    const std::vector<double> before = m.nodes;
    std::vector<double> flat0(m.nTets());
    for (std::size_t t = 0; t < m.nTets(); ++t) flat0[t] = flatness(m, t);
    std::vector<char> moved(m.nNodes(), 0);
    for (std::size_t i = 0; i < m.nNodes(); ++i) {
        if (dimension[i] != 2) continue;
        const Point p = point(m, i), q = tree.closest_point(p);
        if (p == q) continue;
        m.nodes[3 * i] = q.x();
        m.nodes[3 * i + 1] = q.y();
        m.nodes[3 * i + 2] = q.z();
        moved[i] = 1;
    }
    for (int pass = 0; pass < 10; ++pass) {
        bool undone = false;
        for (std::size_t t = 0; t < m.nTets(); ++t) {
            const int32_t* c = &m.tets[4 * t];
            if (!(moved[c[0]] || moved[c[1]] || moved[c[2]] || moved[c[3]])) continue;
            if (tetSixVolume(m, t) > 0 && flatness(m, t) >= 0.5 * flat0[t]) continue;
            for (int k = 0; k < 4; ++k)
                if (moved[c[k]]) {
                    std::copy(before.begin() + 3 * c[k], before.begin() + 3 * c[k] + 3, m.nodes.begin() + 3 * c[k]);
                    moved[c[k]] = 0;
                    undone = true;
                }
        }
        if (!undone) break;
    }
    return static_cast<std::size_t>(std::count(moved.begin(), moved.end(), 1));
}

}  // namespace

std::vector<int32_t> boundaryFeatureEdges(const TetMesh& m, double featureAngleDeg) {
    checkMesh(m);
    return featureEdgesOf(m, extractSurface(m), featureAngleDeg);
}

RemeshResult remeshTets(const TetMesh& input, const RemeshOptions& opt) {
    if (!(std::isfinite(opt.targetEdge)))
        throw InputError(cat("improveMesh: cellSize must be finite (<= 0: the median boundary edge), got ",
                             opt.targetEdge));
    if (opt.iterations < 1 || opt.iterations > 1000)
        throw InputError(cat("improveMesh: iterations must be 1..1000, got ", opt.iterations));
    if (!(opt.featureAngleDeg > 0 && opt.featureAngleDeg < 180))
        throw InputError(cat("improveMesh: featureAngle must be in (0, 180) degrees, got ", opt.featureAngleDeg));
    if (input.nTets() == 0) throw InputError("improveMesh: the mesh has no tetrahedra");
    checkMesh(input);
    TetMesh m = compact(input);
    const Surface s0 = extractSurface(m);  // names a non-manifold surface
    const std::vector<Triangle> inputSurface = surfaceTriangles(m, s0);

    RemeshResult r;
    r.featureEdges = featureEdgesOf(m, s0, opt.featureAngleDeg);
    {
        std::vector<int> degree(m.nNodes(), 0);
        for (int32_t v : r.featureEdges) ++degree[v];
        for (std::size_t v = 0; v < m.nNodes(); ++v)
            if (degree[v] == 1 || degree[v] >= 3) r.corners.push_back(static_cast<int32_t>(v));
    }
    std::vector<double> lengths;
    lengths.reserve(s0.nEdges());
    for (std::size_t e = 0; e < s0.nEdges(); ++e)
        lengths.push_back(std::sqrt(CGAL::squared_distance(point(m, s0.edges[2 * e]), point(m, s0.edges[2 * e + 1]))));
    r.targetEdge = opt.targetEdge > 0 ? opt.targetEdge : median(lengths);
    if (!(r.targetEdge > 0)) throw InputError("improveMesh: the mesh's boundary edges have zero length");

    Tr tr;
    try {
        std::vector<Point> points;
        points.reserve(m.nNodes());
        for (std::size_t i = 0; i < m.nNodes(); ++i) points.push_back(point(m, i));
        std::vector<std::array<int, 5>> cells(m.nTets());
        for (std::size_t t = 0; t < m.nTets(); ++t) {
            for (int k = 0; k < 4; ++k) cells[t][k] = m.tets[4 * t + k];
            cells[t][4] = 1;  // one subdomain: the body
        }
        const std::vector<int32_t>& features = r.featureEdges;
        const std::map<std::array<int, 3>, int> patches = surfacePatches(s0, features, &r.patches);
        std::vector<Vh> handles;
        if (!CGAL::build_triangulation<Tr, false>(tr, points, cells, patches, handles))
            throw InputError("improveMesh: CGAL could not build a triangulation from the mesh (its boundary is not "
                             "a closed manifold surface)");

        // Features inside a patch (a crease that fades out) are constrained too.
        ConstrainedEdges constrained;
        for (std::size_t e = 0; e < features.size() / 2; ++e)
            constrained.edges->insert(orderedPair(handles[features[2 * e] + 1], handles[features[2 * e + 1] + 1]));
        // A pass sometimes leaves an interior sliver (a 64-sided cylinder:
        // 3.9x after 8 iterations, 2.1x after 3 more): more passes while the
        // worst element cuts the step by more than maxStepFactor, with the
        // boundary held (remeshing it again from its own fit drifted: a
        // bumpy ball's volume change went from -0.42 % to -0.88 %).
        // The best round is kept: a round can also make the worst element worse.
        Tr best;
        double bestFactor = std::numeric_limits<double>::infinity();
        for (int round = 0; round <= opt.extraRounds; ++round) {
            CGAL::tetrahedral_isotropic_remeshing(
                tr, r.targetEdge,
                CGAL::parameters::number_of_iterations(
                    static_cast<unsigned>(round == 0 ? opt.iterations : kExtraIterations))
                    .edge_is_constrained_map(constrained)
                    .remesh_boundaries(round == 0)
                    .smooth_constrained_edges(false));
            r.rounds = round + 1;
            const double f = stepFactor(tr);
            if (f <= opt.maxStepFactor) {
                bestFactor = f;
                break;
            }
            if (f < bestFactor) {
                bestFactor = f;
                best = tr;
            }
            if (round == opt.extraRounds) tr.swap(best);
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(cat("improveMesh: CGAL's tetrahedral remeshing failed: ", e.what()));
    }

    std::vector<int> dimension;
    r.mesh = extract(tr, dimension);
    if (r.mesh.nTets() == 0) throw InputError("improveMesh: the remeshed mesh has no tetrahedra");
    try {
        checkMesh(r.mesh);
        r.projected = projectOntoInput(r.mesh, dimension, inputSurface);
        const Surface s1 = extractSurface(r.mesh);
        const std::vector<Triangle> outputSurface = surfaceTriangles(r.mesh, s1);
        r.maxDeviationOut = sampledDistance(outputSurface, inputSurface);
        r.maxDeviationIn = sampledDistance(inputSurface, outputSurface);
        r.maxDeviation = std::max(r.maxDeviationOut, r.maxDeviationIn);
    } catch (const InputError& e) {
        throw InputError(cat("improveMesh: CGAL's remeshing produced an invalid mesh (", e.what(),
                             "); try another cellSize or fewer iterations"));
    }
    return r;
}

}  // namespace qdem
