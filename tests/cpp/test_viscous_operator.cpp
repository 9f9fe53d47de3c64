// The viscous operator C(x) of the implicit update (ViscousOperator.hpp):
// on a strained, rotated element it is symmetric, positive semi-definite,
// zero on the six rigid motions, equal to the explicit viscous force's
// linearisation (it *is* that force), and its diagonal is viscousDiagonal's.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "element/ElementKernel.hpp"
#include "element/ViscousOperator.hpp"

using namespace qdem;

namespace {

using Mat12 = Eigen::Matrix<double, 12, 12>;

// Largest |entry| by a plain loop (Eigen's vectorised maxCoeff on 12x12
// trips GCC 12's false -Wuninitialized in avx512fintrin.h, bug 105593).
template <class M>
double maxAbs(const M& m) {
    double r = 0;
    for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j) r = std::max(r, std::abs(m(i, j)));
    return r;
}

struct Tet {
    double X[12];       // current node positions
    double B[9];        // inverse reference edge matrix, row-major
    double V0;
    int32_t conn[4] = {0, 1, 2, 3};
};

Tet strainedTet() {
    Mat3 Dm;
    Dm << 1.0, 0.2, 0.1, 0.0, 0.9, 0.3, 0.1, 0.0, 1.1;  // reference edges (columns)
    Tet t;
    const Mat3 Bm = Dm.inverse();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t.B[3 * i + j] = Bm(i, j);
    t.V0 = Dm.determinant() / 6;
    // current shape: a stretch, a shear and a large rotation
    Mat3 F;
    F << 1.3, 0.2, 0.0, -0.1, 0.8, 0.1, 0.05, 0.0, 1.1;
    const Mat3 R = Eigen::AngleAxisd(2.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    const Mat3 Ds = R * F * Dm;
    const Vec3 x0(0.3, -0.2, 0.5);
    for (int i = 0; i < 3; ++i) t.X[i] = x0[i];
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) t.X[3 * (k + 1) + i] = x0[i] + Ds(i, k);
    return t;
}

// C p on one element through the batch kernel with the viscous-only law.
Eigen::Matrix<double, 12, 1> applyC(const Tet& t, const ElementParams& p, const Eigen::Matrix<double, 12, 1>& v) {
    BatchOut out;
    elementBatch<ViscousStressOnly, true, false>(ViscousStressOnly{}, 0, 1, t.conn, t.X, v.data(), t.B, &t.V0, p, out);
    Eigen::Matrix<double, 12, 1> y;
    for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) y[3 * a + i] = -out.f[a][i][0];
    return y;
}

Mat12 assembleC(const Tet& t, const ElementParams& p) {
    Mat12 C;
    for (int j = 0; j < 12; ++j) C.col(j) = applyC(t, p, Eigen::Matrix<double, 12, 1>::Unit(j));
    return C;
}

// Eigenvalues of a symmetric 12x12.  GCC 12's false "used uninitialized"
// inside avx512fintrin.h once Eigen's solver is inlined (bug 105593, as in
// pkg/world/StableDt.cpp): silenced for this function only.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif
__attribute__((noinline)) Eigen::Matrix<double, 12, 1> eigenvalues(const Mat12& C) {
    Eigen::SelfAdjointEigenSolver<Mat12> es(C, Eigen::EigenvaluesOnly);
    return es.eigenvalues();
}
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic pop
#endif

}  // namespace

TEST(ViscousOperator, SymmetricPositiveSemiDefiniteAndZeroOnRigidMotions) {
    const Tet t = strainedTet();
    const ElementParams p{2e6, 1e6, 1e-3};
    const Mat12 C = assembleC(t, p);
    const double scale = maxAbs(C);
    EXPECT_LT(maxAbs(Mat12(C - C.transpose())), 1e-12 * scale);
    const Eigen::Matrix<double, 12, 1> ev = eigenvalues(0.5 * (C + C.transpose()));
    EXPECT_GT(ev.minCoeff(), -1e-12 * scale);
    // six zero eigenvalues (3 translations, 3 spins about the current shape), six positive
    int zeros = 0;
    for (int k = 0; k < 12; ++k) zeros += ev[k] < 1e-10 * scale;
    EXPECT_EQ(zeros, 6);
    // a rigid spin about the current shape: no viscous force
    const Vec3 w(0.3, -1.1, 0.7), c(1, 2, 3);
    Eigen::Matrix<double, 12, 1> v;
    for (int a = 0; a < 4; ++a) v.segment<3>(3 * a) = c + w.cross(Vec3(t.X[3 * a], t.X[3 * a + 1], t.X[3 * a + 2]));
    EXPECT_LT(maxAbs(C * v), 1e-12 * scale * maxAbs(v));
}

TEST(ViscousOperator, ForcesSumToZeroAndPowerIsTheDissipation) {
    const Tet t = strainedTet();
    const ElementParams p{2e6, 1e6, 1e-3};
    Eigen::Matrix<double, 12, 1> v;
    for (int k = 0; k < 12; ++k) v[k] = std::sin(1.7 * k + 0.3);
    const Eigen::Matrix<double, 12, 1> y = applyC(t, p, v);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(y[i] + y[3 + i] + y[6 + i] + y[9 + i], 0.0, 1e-12 * maxAbs(y));
    // v.C v = V0 S_v : dE/dt, the dissipation the explicit kernel books
    Mat3 Ds, Vd;
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) {
            Ds(i, k) = t.X[3 * (k + 1) + i] - t.X[i];
            Vd(i, k) = v[3 * (k + 1) + i] - v[i];
        }
    const Mat3 B = loadRowMajor(t.B);
    Mat3 Ed;
    const Mat3 Sv = viscousStress(Ds * B, Vd * B, p, &Ed);
    EXPECT_NEAR(v.dot(y), t.V0 * (Sv.array() * Ed.array()).sum(), 1e-12 * std::abs(v.dot(y)));
}

TEST(ViscousOperator, DiagonalIsTheAssembledOnes) {
    const Tet t = strainedTet();
    const ElementParams p{2e6, 1e6, 1e-3};
    const Mat12 C = assembleC(t, p);
    Mat3 Ds;
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) Ds(i, k) = t.X[3 * (k + 1) + i] - t.X[i];
    const Mat3 B = loadRowMajor(t.B);
    double d[4][3];
    viscousDiagonal(Ds * B, B, t.V0, p, d);
    for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(d[a][i], C(3 * a + i, 3 * a + i), 1e-12 * maxAbs(C.diagonal()));
}

// The co-rotated preconditioner's premise (CorotatedCholesky.hpp): for the
// reference shape turned rigidly by R, C(x) = R K R^T node-blockwise, K the
// reference matrix viscousReferenceMatrix gives (F = I: C(x) = K itself).
TEST(ViscousOperator, RigidlyTurnedReferenceIsTheRotatedReferenceMatrix) {
    Tet t = strainedTet();  // its B and V0; the shape set here
    const Mat3 Dm = loadRowMajor(t.B).inverse();
    const Mat3 R = Eigen::AngleAxisd(2.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    const ElementParams p{2e6, 1e6, 1e-3};
    double Kr[12][12];
    viscousReferenceMatrix(loadRowMajor(t.B), t.V0, p, Kr);
    Mat12 K, Rb = Mat12::Zero();
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) K(i, j) = Kr[i][j];
    for (int a = 0; a < 4; ++a) Rb.block<3, 3>(3 * a, 3 * a) = R;
    for (const Mat3& turn : {Mat3(Mat3::Identity()), R}) {
        const Mat3 Ds = turn * Dm;
        for (int i = 0; i < 3; ++i) t.X[i] = 0.1 * i;
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i) t.X[3 * (k + 1) + i] = t.X[i] + Ds(i, k);
        const Mat12 C = assembleC(t, p);
        const Mat12 expected = turn.isIdentity() ? K : Mat12(Rb * K * Rb.transpose());
        EXPECT_LT(maxAbs(Mat12(C - expected)), 1e-12 * maxAbs(C));
    }
    // and a strained shape is not: what the preconditioner misses is the strain
    const Mat12 Cs = assembleC(strainedTet(), p);
    EXPECT_GT(maxAbs(Mat12(Cs - Rb * K * Rb.transpose())), 1e-2 * maxAbs(Cs));
}
