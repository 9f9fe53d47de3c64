#include "ShortFeatures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <unordered_map>
#include <utility>

namespace qdem {
namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

struct Edge {
    std::size_t a, b;     // vertices, a < b
    std::size_t t0, t1;   // its two triangles
};

std::vector<Edge> edgesOf(const std::vector<std::array<std::size_t, 3>>& tris) {
    std::unordered_map<uint64_t, std::size_t> index;
    std::vector<Edge> edges;
    edges.reserve(tris.size() * 3 / 2);
    for (std::size_t t = 0; t < tris.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const std::size_t a = std::min(tris[t][k], tris[t][(k + 1) % 3]);
            const std::size_t b = std::max(tris[t][k], tris[t][(k + 1) % 3]);
            const uint64_t key = (static_cast<uint64_t>(a) << 32) | static_cast<uint64_t>(b);
            const auto [it, added] = index.emplace(key, edges.size());
            if (added) edges.push_back({a, b, t, t});
            else edges[it->second].t1 = t;
        }
    return edges;
}

// Union-find over vertices, for the sets of sharp edges joined at vertices.
std::size_t root(std::vector<std::size_t>& parent, std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

}  // namespace

ShortFeatureReport smoothShortFeatures(std::vector<Vec>& points, const std::vector<std::array<std::size_t, 3>>& tris,
                                       double featureAngleDeg, double minLength) {
    ShortFeatureReport report;
    if (!(minLength > 0) || tris.empty()) return report;
    const double cosFeature = std::cos(featureAngleDeg * M_PI / 180.0);
    const std::vector<Edge> edges = edgesOf(tris);
    // Each vertex's neighbours (the other ends of its edges).
    std::vector<std::vector<std::size_t>> ring(points.size());
    for (const Edge& e : edges) ring[e.a].push_back(e.b), ring[e.b].push_back(e.a);
    const std::vector<Vec> start = points;
    // A few rounds: moving a feature's vertices can make a neighbouring edge
    // sharp; that one is found and smoothed in the next round.
    constexpr int kRounds = 20;
    for (int round = 0; round < kRounds; ++round) {
        std::vector<Vec> normal(tris.size());
        for (std::size_t t = 0; t < tris.size(); ++t) {
            const Vec n = cross(sub(points[tris[t][1]], points[tris[t][0]]), sub(points[tris[t][2]], points[tris[t][0]]));
            const double l = norm(n);
            normal[t] = l > 0 ? Vec{n[0] / l, n[1] / l, n[2] / l} : Vec{0, 0, 0};
        }
        std::vector<std::size_t> parent(points.size());
        std::iota(parent.begin(), parent.end(), std::size_t{0});
        std::vector<uint8_t> onSharp(points.size(), 0);
        std::vector<const Edge*> sharp;
        for (const Edge& e : edges)
            if (e.t0 != e.t1 && dot(normal[e.t0], normal[e.t1]) < cosFeature) {
                sharp.push_back(&e);
                onSharp[e.a] = onSharp[e.b] = 1;
                parent[root(parent, e.a)] = root(parent, e.b);
            }
        std::unordered_map<std::size_t, double> length;  // per set (its root)
        for (const Edge* e : sharp) length[root(parent, e->a)] += norm(sub(points[e->a], points[e->b]));
        std::size_t shortSets = 0;
        for (const auto& [r, l] : length) shortSets += l < minLength;
        if (round == 0) report.kept = length.size() - shortSets, report.smoothed = shortSets;
        if (shortSets == 0) break;
        // Jacobi-style, from the positions at the start of the round: every
        // vertex of a short set moves towards its neighbours' mean, along its
        // normal only (the crease flattens; the vertex does not slide over
        // the surface towards far neighbours, as on a CAD part's long thin
        // triangles), and by at most half its shortest edge (no triangle
        // turns over).
        std::vector<Vec> vertexNormal(points.size(), Vec{0, 0, 0});
        for (std::size_t t = 0; t < tris.size(); ++t) {
            const Vec a = cross(sub(points[tris[t][1]], points[tris[t][0]]), sub(points[tris[t][2]], points[tris[t][0]]));
            for (std::size_t v : tris[t])
                for (int d = 0; d < 3; ++d) vertexNormal[v][d] += a[d];  // area-weighted
        }
        std::vector<std::pair<std::size_t, Vec>> moves;
        for (std::size_t v = 0; v < points.size(); ++v) {
            if (!onSharp[v] || length[root(parent, v)] >= minLength || ring[v].empty()) continue;
            Vec m{0, 0, 0};
            double shortest = std::numeric_limits<double>::infinity();
            for (std::size_t w : ring[v]) {
                for (int d = 0; d < 3; ++d) m[d] += points[w][d];
                shortest = std::min(shortest, norm(sub(points[w], points[v])));
            }
            for (int d = 0; d < 3; ++d) m[d] = m[d] / static_cast<double>(ring[v].size()) - points[v][d];
            const double ln = norm(vertexNormal[v]);
            if (!(ln > 0)) continue;
            const Vec n{vertexNormal[v][0] / ln, vertexNormal[v][1] / ln, vertexNormal[v][2] / ln};
            double step = dot(m, n);
            step = std::clamp(step, -0.5 * shortest, 0.5 * shortest);
            moves.emplace_back(v, Vec{points[v][0] + step * n[0], points[v][1] + step * n[1], points[v][2] + step * n[2]});
        }
        for (const auto& [v, m] : moves) points[v] = m;
    }
    for (std::size_t v = 0; v < points.size(); ++v)
        report.longestMoved = std::max(report.longestMoved, norm(sub(points[v], start[v])));
    return report;
}

}  // namespace qdem
