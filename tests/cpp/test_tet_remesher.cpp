// CGAL tetrahedral remeshing of an existing mesh: only built with CGAL.
#ifdef QDEM_HAVE_CGAL

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/Errors.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Surface.hpp"
#include "mesh/TetMesh.hpp"
#include "mesh/TetRemesher.hpp"

using namespace qdem;

namespace {

double volume(const TetMesh& m) {
    double v = 0;
    for (std::size_t t = 0; t < m.nTets(); ++t) v += tetSixVolume(m, t) / 6.0;
    return v;
}

// Smallest height over largest face, against the longest edge, of all tets.
double worstFlatness(const TetMesh& m) {
    double worst = 1;
    for (std::size_t t = 0; t < m.nTets(); ++t) {
        const int32_t* c = &m.tets[4 * t];
        double maxCross = 0, maxEdge = 0;
        auto p = [&](int k, int i) { return m.nodes[3 * c[k] + i]; };
        for (int k = 0; k < 4; ++k) {
            const int a = (k + 1) % 4, b = (k + 2) % 4, d = (k + 3) % 4;
            double u[3], w[3];
            for (int i = 0; i < 3; ++i) u[i] = p(b, i) - p(a, i), w[i] = p(d, i) - p(a, i);
            const double cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2], cz = u[0] * w[1] - u[1] * w[0];
            maxCross = std::max(maxCross, std::sqrt(cx * cx + cy * cy + cz * cz));
            for (int j = k + 1; j < 4; ++j) {
                double e2 = 0;
                for (int i = 0; i < 3; ++i) e2 += (p(k, i) - p(j, i)) * (p(k, i) - p(j, i));
                maxEdge = std::max(maxEdge, std::sqrt(e2));
            }
        }
        worst = std::min(worst, std::fabs(tetSixVolume(m, t)) / maxCross / maxEdge);
    }
    return worst;
}

// A unit cube of 4^3 Kuhn cells whose node at the middle of the top face
// (z = 0.5) is pushed down almost into the layer below: tets nearly flat.
TetMesh cubeWithSlivers() {
    TetMesh m = boxMesh(4, 4, 4, 1.0, 1.0, 1.0, 6);
    for (std::size_t i = 0; i < m.nNodes(); ++i)
        if (std::fabs(m.nodes[3 * i]) < 1e-12 && std::fabs(m.nodes[3 * i + 1]) < 1e-12 &&
            std::fabs(m.nodes[3 * i + 2]) < 1e-12)
            m.nodes[3 * i + 2] = 0.2499;  // centre node, almost onto the plane z = 0.25 of its neighbours
    return m;
}

}  // namespace

TEST(TetRemesher, RemovesSliversAndKeepsTheCubeExactly) {
    const TetMesh in = cubeWithSlivers();
    ASSERT_LT(worstFlatness(in), 1e-3);
    const RemeshResult r = remeshTets(in, RemeshOptions{});
    checkMesh(r.mesh);
    EXPECT_GT(worstFlatness(r.mesh), 0.1);
    EXPECT_NEAR(volume(r.mesh), 1.0, 1e-12);
    EXPECT_LT(r.maxDeviation, 1e-12);
    EXPECT_EQ(r.patches, 6u);
    EXPECT_EQ(r.corners.size(), 8u);
    // every boundary node on a face of the cube, the corners still nodes
    const Surface s = extractSurface(r.mesh);
    for (int32_t v : s.nodes) {
        double d = 1;
        for (int i = 0; i < 3; ++i) d = std::min(d, 0.5 - std::fabs(r.mesh.nodes[3 * v + i]));
        EXPECT_LT(std::fabs(d), 1e-12);
    }
    int corners = 0;
    for (std::size_t v = 0; v < r.mesh.nNodes(); ++v)
        corners += std::fabs(r.mesh.nodes[3 * v]) == 0.5 && std::fabs(r.mesh.nodes[3 * v + 1]) == 0.5 &&
                   std::fabs(r.mesh.nodes[3 * v + 2]) == 0.5;
    EXPECT_EQ(corners, 8);
}

TEST(TetRemesher, RefusesBadInputWithAMessage) {
    TetMesh m = boxMesh(2, 2, 2, 1.0, 1.0, 1.0, 6);
    RemeshOptions opt;
    opt.iterations = 0;
    EXPECT_THROW(remeshTets(m, opt), InputError);
    opt = RemeshOptions{};
    opt.featureAngleDeg = 200;
    EXPECT_THROW(remeshTets(m, opt), InputError);
    std::swap(m.tets[2], m.tets[3]);  // an inverted tet
    try {
        remeshTets(m, RemeshOptions{});
        FAIL() << "an inverted tet was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("nverted"), std::string::npos) << e.what();
    }
    EXPECT_THROW(remeshTets(TetMesh{}, RemeshOptions{}), InputError);
}

#endif  // QDEM_HAVE_CGAL
