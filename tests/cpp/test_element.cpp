// Element kernel: objectivity, patch test, batch kernel == reference kernel.
#include <gtest/gtest.h>

#include <type_traits>

#include <memory>

#include <Eigen/Geometry>
#include <cmath>

#include "element/ElementKernel.hpp"
#include "element/MaterialLaw.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

// (by pointer: a World is not copied or moved, its phases refer to it)
std::unique_ptr<World> cubeWorld(double viscosity = 0.0, MaterialLaw law = MaterialLaw::StableNeoHookean) {
    auto wp = std::make_unique<World>();
    World& w = *wp;
    Material m;
    m.viscosity = viscosity;
    m.law = law;
    w.addPiece(boxMesh(3, 3, 3, 1.0, 1.0, 1.0, 6), w.addMaterial(m));
    return wp;
}

// Maps every node x -> A x + b (positions) and sets velocities L x.
void affine(World& w, const Eigen::Matrix3d& A, const Eigen::Vector3d& b, const Eigen::Matrix3d& L) {
    for (std::size_t n = 0; n < w.nNodes(); ++n) {
        Eigen::Map<const Eigen::Vector3d> X(&w.refPos[3 * n]);
        Eigen::Map<Eigen::Vector3d>(&w.pos[3 * n]) = A * X + b;
        Eigen::Map<Eigen::Vector3d>(&w.vel[3 * n]) = L * X;
    }
}

double maxAbsStress(const World& w) {
    std::vector<double> s(6 * w.nTets());
    w.computeStress(s.data());
    double m = 0;
    for (double v : s) m = std::max(m, std::fabs(v));
    return m;
}

}  // namespace

TEST(Element, RigidRotationGivesNoStress) {
    for (double angle : {M_PI / 2, M_PI, 2.3}) {
        const auto wOwner = cubeWorld(0.0);
        World& w = *wOwner;
        const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
        affine(w, R, Eigen::Vector3d(5, -2, 1), Eigen::Matrix3d::Zero());
        // Stress relative to E: rounding level.
        EXPECT_LT(maxAbsStress(w) / 5e8, 1e-13) << "angle " << angle;
    }
}

TEST(Element, RigidSpinGivesNoViscousStress) {
    // Spinning about an axis: the velocity gradient is skew, dE/dt = 0.
    const auto wOwner = cubeWorld(2.5e5);
        World& w = *wOwner;
    Eigen::Matrix3d W;
    W << 0, -3, 2, 3, 0, -1, -2, 1, 0;
    affine(w, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), W);
    EXPECT_LT(maxAbsStress(w), 1e-6);
}

TEST(Element, PatchTestUniformStressZeroInteriorForce) {
    const auto wOwner = cubeWorld(0.0);
        World& w = *wOwner;
    Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
    A(0, 0) += 1e-3;
    A(0, 1) += 4e-4;
    A(2, 1) -= 2e-4;
    A(1, 1) -= 5e-4;
    affine(w, A, Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Matrix3d::Zero());
    std::vector<double> s(6 * w.nTets());
    w.computeStress(s.data());
    for (std::size_t e = 1; e < w.nTets(); ++e)
        for (int c = 0; c < 6; ++c) EXPECT_NEAR(s[6 * e + c], s[c], 1e-9 * std::fabs(s[0]));
    // One step with dt tiny: the force array holds the internal forces.
    w.step(1e-12);
    const Surface& surf = w.pieces[0].surface;
    double fmax = 0, finterior = 0;
    for (std::size_t n = 0; n < w.nNodes(); ++n) {
        const double f = Eigen::Map<const Eigen::Vector3d>(&w.force[3 * n]).norm();
        fmax = std::max(fmax, f);
        if (!std::binary_search(surf.nodes.begin(), surf.nodes.end(), static_cast<int32_t>(n)))
            finterior = std::max(finterior, f);
    }
    EXPECT_GT(fmax, 0);
    EXPECT_LT(finterior, 1e-10 * fmax);
}

TEST(Element, ForcesSumToZero) {
    const auto wOwner = cubeWorld(2.5e5);
        World& w = *wOwner;
    Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + 0.05 * Eigen::Matrix3d::Random();
    affine(w, A, Eigen::Vector3d::Zero(), 0.3 * Eigen::Matrix3d::Random());
    for (std::size_t n = 0; n < w.nNodes(); ++n) w.pos[3 * n] += 1e-3 * std::sin(3.0 * n);
    w.step(1e-12);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double scale = 0;
    for (std::size_t n = 0; n < w.nNodes(); ++n) {
        sum += Eigen::Map<const Eigen::Vector3d>(&w.force[3 * n]);
        scale += Eigen::Map<const Eigen::Vector3d>(&w.force[3 * n]).norm();
    }
    EXPECT_LT(sum.norm(), 1e-12 * scale);
}

TEST(Element, BatchKernelMatchesReference) {
    for (MaterialLaw lawTag : {MaterialLaw::StableNeoHookean, MaterialLaw::SaintVenantKirchhoff}) {
        const auto wOwner = cubeWorld(1e5, lawTag);
        World& w = *wOwner;
        Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + 0.1 * Eigen::Matrix3d::Random();
        affine(w, A, Eigen::Vector3d::Zero(), 0.5 * Eigen::Matrix3d::Random());
        for (std::size_t i = 0; i < w.pos.size(); ++i) w.pos[i] += 1e-2 * std::cos(1.7 * i);
        // One element forced inverted (its node 0 mirrored through the
        // opposite face): the kernels must agree there too.
        {
            const int32_t* c = &w.tetNodes[4 * 5];
            const Eigen::Map<const Vec3> x1(&w.pos[3 * c[1]]), x2(&w.pos[3 * c[2]]), x3(&w.pos[3 * c[3]]);
            Eigen::Map<Vec3> x0(&w.pos[3 * c[0]]);
            const Vec3 n = (x2 - x1).cross(x3 - x1).normalized();
            x0 -= 2 * (x0 - x1).dot(n) * n;
        }
        const Material& m = w.materials[0];
        const ElementParams p{m.lambda(), m.mu(), m.beta()};
        // Every compiled combination (viscous or not, energy or not): each is
        // its own code, with the scale -V0 folded into different constants.
        auto check = [&](const auto& law, auto viscousTag, auto energyTag) {
            using Law = std::decay_t<decltype(law)>;
            constexpr bool Viscous = decltype(viscousTag)::value, Energy = decltype(energyTag)::value;
            const ElementParams pv{p.lambda, p.mu, Viscous ? p.beta : 0.0};
            BatchOut out;
            elementBatch<Law, Viscous, Energy>(law, 3, 5, w.tetNodes.data(), w.pos.data(), w.vel.data(),
                                               w.tetB.data(), w.tetVol0.data(), pv, out);
            for (int l = 0; l < 5; ++l) {
                const int e = 3 + l;
                const int32_t* c = &w.tetNodes[4 * e];
                const Mat3 B = loadRowMajor(&w.tetB[9 * e]);
                const Mat3 F = edgeMatrix(&w.pos[3 * c[0]], &w.pos[3 * c[1]], &w.pos[3 * c[2]], &w.pos[3 * c[3]]) * B;
                const Mat3 Fd =
                    edgeMatrix(&w.vel[3 * c[0]], &w.vel[3 * c[1]], &w.vel[3 * c[2]], &w.vel[3 * c[3]]) * B;
                const TetStress st = tetStress<Law, Viscous, true>(law, F, Fd, pv);
                double f[4][3];
                nodalForces(st.P, B, w.tetVol0[e], f);
                for (int k = 0; k < 4; ++k)
                    for (int i = 0; i < 3; ++i)
                        EXPECT_NEAR(out.f[k][i][l], f[k][i], 1e-9 * (1 + std::fabs(f[k][i])))
                            << lawName(m.law) << " viscous " << Viscous << " energy " << Energy;
                if (Energy) {
                    EXPECT_NEAR(out.wElastic[l], w.tetVol0[e] * st.wElastic, 1e-9 * std::fabs(out.wElastic[l]) + 1e-12)
                        << lawName(m.law);
                    EXPECT_NEAR(out.diss[l], w.tetVol0[e] * st.dissRate, 1e-9 * std::fabs(out.diss[l]) + 1e-12);
                    if (Viscous) {
                        EXPECT_GT(out.diss[l], 0) << "a deforming viscous element dissipates";
                    }
                }
                if (e == 5) {
                    EXPECT_LT(F.determinant(), 0);
                }
            }
        };
        withLaw(m, [&](const auto& law) {
            check(law, std::true_type{}, std::true_type{});
            check(law, std::true_type{}, std::false_type{});
            check(law, std::false_type{}, std::true_type{});
            check(law, std::false_type{}, std::false_type{});
        });
    }
}
