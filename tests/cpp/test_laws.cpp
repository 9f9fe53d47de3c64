// Material laws (pkg/element/laws): each law's stress is the derivative of
// its energy, its tangent the derivative of its stress (finite differences,
// inverted states included), both are stress-free at rest and under
// rotations, equal Hooke's law at small strain for any Poisson ratio, and
// the Stable Neo-Hookean pushes an inverted element back where
// Saint-Venant-Kirchhoff has a stress-free mirror state.
#include <gtest/gtest.h>

#include <memory>

#include <Eigen/Geometry>
#include <cmath>
#include <type_traits>

#include "element/MaterialLaw.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

Material material(MaterialLaw law, double nu) {
    Material m;
    m.young = 2e6;
    m.poisson = nu;
    m.law = law;
    return m;
}

// Every declared law (QDEM_MATERIAL_LAWS): a new law is tested without an edit here.
const auto& kLaws = kMaterialLaws;

// Deformation gradients to test at: stretched, sheared, compressed past
// SVK's limit point, flattened almost to zero volume, and inverted.
std::vector<Mat3> someF() {
    std::vector<Mat3> Fs;
    Mat3 F;
    F << 1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.3;
    Fs.push_back(F);
    Fs.push_back(Eigen::Vector3d(0.4, 1.1, 0.95).asDiagonal());
    Fs.push_back(Eigen::Vector3d(0.02, 1, 1).asDiagonal());
    F << -0.6, 0.1, 0.2, 0.0, 1.0, -0.3, 0.1, 0.2, 0.8;  // J < 0
    Fs.push_back(F);
    Fs.push_back(Eigen::Vector3d(-1, 1, 1).asDiagonal());  // SVK's mirror state
    Fs.push_back(-Mat3::Identity() + 0.1 * Mat3::Random());  // point-inverted
    return Fs;
}

}  // namespace

TEST(Laws, StressIsTheEnergyDerivative) {
    for (MaterialLaw tag : kLaws)
        for (double nu : {0.0, 0.3, 0.49})
            withLaw(material(tag, nu), [&](const auto& law) {
                for (const Mat3& F : someF()) {
                    const Mat3 P = law.piola(F);
                    const double h = 1e-6;
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j) {
                            Mat3 Fp = F, Fm = F;
                            Fp(i, j) += h;
                            Fm(i, j) -= h;
                            const double fd = (law.energy(Fp) - law.energy(Fm)) / (2 * h);
                            EXPECT_NEAR(P(i, j), fd, 1e-6 * (P.norm() + 1e4))
                                << lawName(tag) << " nu " << nu << " J " << F.determinant();
                        }
                }
            });
}

TEST(Laws, TangentIsTheStressDerivative) {
    for (MaterialLaw tag : kLaws)
        for (double nu : {0.0, 0.3, 0.49})
            withLaw(material(tag, nu), [&](const auto& law) {
                for (const Mat3& F : someF()) {
                    const Mat9 A = law.tangent(F);
                    const double h = 1e-6;
                    for (int k = 0; k < 3; ++k)
                        for (int L = 0; L < 3; ++L) {
                            Mat3 Fp = F, Fm = F;
                            Fp(k, L) += h;
                            Fm(k, L) -= h;
                            const Mat3 dP = (law.piola(Fp) - law.piola(Fm)) / (2 * h);
                            for (int i = 0; i < 3; ++i)
                                for (int J = 0; J < 3; ++J)
                                    EXPECT_NEAR(A(3 * i + J, 3 * k + L), dP(i, J), 1e-6 * A.norm())
                                        << lawName(tag) << " nu " << nu << " J " << F.determinant();
                        }
                }
            });
}

TEST(Laws, StressFreeAtRestAndUnderRotations) {
    for (MaterialLaw tag : kLaws)
        for (double nu : {0.0, 0.3, 0.49}) {
            const Material m = material(tag, nu);
            withLaw(m, [&](const auto& law) {
                for (double angle : {0.0, 0.3, M_PI / 2, M_PI, 2.3}) {
                    const Mat3 R =
                        Eigen::AngleAxisd(angle, Eigen::Vector3d(1, -2, 3).normalized()).toRotationMatrix();
                    // Relative to the P-wave modulus: rounding level.
                    EXPECT_LT(law.piola(R).norm() / m.pWaveModulus(), 1e-14) << lawName(tag) << " " << angle;
                    EXPECT_LT(std::fabs(law.energy(R)) / m.pWaveModulus(), 1e-14) << lawName(tag) << " " << angle;
                }
            });
        }
}

TEST(Laws, SmallStrainTangentIsHooke) {
    for (MaterialLaw tag : kLaws)
        for (double nu : {-0.5, 0.0, 0.25, 0.4, 0.49}) {
            const Material m = material(tag, nu);
            const double lam = m.lambda(), mu = m.mu();
            withLaw(m, [&](const auto& law) {
                const Mat9 A = law.tangent(Mat3::Identity());
                for (int i = 0; i < 3; ++i)
                    for (int J = 0; J < 3; ++J)
                        for (int k = 0; k < 3; ++k)
                            for (int L = 0; L < 3; ++L) {
                                // C_iJkL = lambda d_iJ d_kL + mu (d_ik d_JL + d_iL d_kJ)
                                const double hooke = (i == J && k == L ? lam : 0.0) +
                                                     mu * ((i == k && J == L ? 1.0 : 0.0) + (i == L && k == J ? 1.0 : 0.0));
                                EXPECT_NEAR(A(3 * i + J, 3 * k + L), hooke, 1e-12 * (std::fabs(lam) + 2 * mu))
                                    << lawName(tag) << " nu " << nu;
                            }
                double l0, m0;
                law.lameAtRest(l0, m0);  // what the reference stable step uses
                EXPECT_NEAR(l0, lam, 1e-12 * (std::fabs(lam) + mu));
                EXPECT_NEAR(m0, mu, 1e-12 * mu);
            });
        }
}

TEST(Laws, StableNeoHookeanPushesInvertedElementsBack) {
    const Material m = material(MaterialLaw::StableNeoHookean, 0.3);
    const StableNeoHookean snh(m.lambda(), m.mu());
    for (const Mat3& F : someF()) {
        if (F.determinant() > 0) continue;
        // The elastic force is -dPsi/dF = -P; the volume changes along it
        // at the rate dJ/dF : (-P) = -cof(F) : P, which must be > 0.
        const double rate = -(StableNeoHookean::cofactor(F).array() * snh.piola(F).array()).sum();
        EXPECT_GT(rate, 0.1 * m.young) << "J " << F.determinant();
    }
    // Uniaxial strain F = diag(s, 1, 1): the nominal stress grows
    // monotonically from full inversion (s = -1) to tension (s = 2) ...
    double prev = -1e300;
    for (double s = -1; s <= 2; s += 0.01) {
        const double P11 = snh.piola(Eigen::Vector3d(s, 1, 1).asDiagonal())(0, 0);
        EXPECT_GT(P11, prev) << s;
        prev = P11;
    }
    // ... and compression (s < 1) is resisted everywhere, inverted included.
    for (double s : {-1.0, -0.5, 0.0, 0.3, 0.9})
        EXPECT_LT(snh.piola(Eigen::Vector3d(s, 1, 1).asDiagonal())(0, 0), 0) << s;
}

TEST(Laws, SaintVenantKirchhoffLimitPointAndMirrorState) {
    const Material m = material(MaterialLaw::SaintVenantKirchhoff, 0.3);
    const SaintVenantKirchhoff svk(m.lambda(), m.mu());
    auto P11 = [&](double s) { return svk.piola(Eigen::Vector3d(s, 1, 1).asDiagonal())(0, 0); };
    // P11 = (lambda + 2 mu) s (s^2 - 1)/2: the compressive peak at 1/sqrt(3).
    const double s0 = 1 / std::sqrt(3.0);
    EXPECT_NEAR(P11(s0), -m.pWaveModulus() / (3 * std::sqrt(3.0)), 1e-12 * m.young);
    EXPECT_GT(P11(s0 - 0.05), P11(s0));
    EXPECT_GT(P11(s0 + 0.05), P11(s0));
    EXPECT_EQ(P11(0.0), 0.0);  // flattened: no resistance
    // The mirror state carries no stress and no energy: nothing pushes back.
    const Mat3 M = Eigen::Vector3d(-1, 1, 1).asDiagonal();
    EXPECT_EQ(svk.piola(M).norm(), 0.0);
    EXPECT_EQ(svk.energy(M), 0.0);
}

namespace {

// A 2x2x2-cell block whose corner node 0 (in one tet only, 5 tets per cell)
// is mirrored through that tet's opposite face and pushed `depth` times as
// far beyond it: the tet is inverted (volume ratio -depth).
// (by pointer: a World is not copied or moved, its phases refer to it)
std::unique_ptr<World> invertedBlock(MaterialLaw law, double depth, int& badTet) {
    auto wp = std::make_unique<World>();
    World& w = *wp;
    Material m = material(law, 0.3);
    m.viscosity = 0;
    w.addPiece(boxMesh(2, 2, 2, 0.1, 0.1, 0.1, 5), w.addMaterial(m));
    int node = -1;  // a node in exactly one tet
    for (std::size_t n = 0; n < w.nNodes() && node < 0; ++n) {
        int count = 0;
        for (std::size_t t = 0; t < w.nTets(); ++t)
            for (int k = 0; k < 4; ++k)
                if (w.tetNodes[4 * t + k] == static_cast<int32_t>(n)) count++, badTet = static_cast<int>(t);
        if (count == 1) node = static_cast<int>(n);
    }
    const int32_t* c = &w.tetNodes[4 * badTet];
    int others[3], j = 0;
    for (int k = 0; k < 4; ++k)
        if (c[k] != node) others[j++] = c[k];
    const Eigen::Map<const Vec3> a(&w.pos[3 * others[0]]), b(&w.pos[3 * others[1]]), d(&w.pos[3 * others[2]]);
    Eigen::Map<Vec3> x(&w.pos[3 * node]);
    const Vec3 n = (b - a).cross(d - a).normalized();
    x -= (1 + depth) * (x - a).dot(n) * n;
    return wp;
}

}  // namespace

TEST(Laws, InvertedElementsAreCountedAndSvkStops) {
    int bad = -1;
    const auto snhOwner = invertedBlock(MaterialLaw::StableNeoHookean, 1.0, bad);
        World& snh = *snhOwner;
    const InversionCount r = snh.checkInverted();
    EXPECT_EQ(r.count, 1);
    EXPECT_EQ(r.unrecoverable, 0);
    EXPECT_EQ(r.piece, 0);
    EXPECT_EQ(r.element, bad);
    EXPECT_NEAR(r.volumeRatio, -1.0, 1e-12);
    const auto svkOwner = invertedBlock(MaterialLaw::SaintVenantKirchhoff, 1.0, bad);
        World& svk = *svkOwner;
    EXPECT_EQ(svk.countInverted().unrecoverable, 1);
    try {
        svk.checkInverted();
        FAIL() << "no exception";
    } catch (const StabilityError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("tetrahedron " + std::to_string(bad) + " of piece 0 is inverted (volume ratio -1"),
                  std::string::npos)
            << msg;
        EXPECT_NE(msg.find("law='stableNeoHookean'"), std::string::npos) << msg;
    }
    // The default law pushes it back: positive within a few steps.
    const double dt = 0.5 * snh.stableDt().combined;
    int steps = 0;
    while (snh.countInverted().count > 0 && steps < 1000) snh.step(dt), ++steps;
    EXPECT_LT(steps, 50);
}

TEST(Laws, CurrentStepCheckNamesAnInvertedElementAsInverted) {
    // Inverted and stretched three times its height: stiffer than the
    // reference step allows, for either law; the message says inverted.
    for (MaterialLaw tag : kLaws) {
        int bad = -1;
        const auto wOwner = invertedBlock(tag, 3.0, bad);
        World& w = *wOwner;
        const double dt = 0.99 * w.stableDt().combined;
        try {
            w.checkCurrentDt(dt);
            FAIL() << "no exception " << lawName(tag);
        } catch (const StabilityError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("tetrahedron " + std::to_string(bad) + " of piece 0 is inverted (volume ratio -3"),
                      std::string::npos)
                << msg;
            EXPECT_EQ(msg.find("sliver"), std::string::npos) << msg;
        }
    }
}
