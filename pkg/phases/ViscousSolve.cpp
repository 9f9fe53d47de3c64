// Semi-implicit Kelvin-Voigt viscosity: preconditioned conjugate gradients
// (Jacobi, or the co-rotated Cholesky factor of CorotatedCholesky.hpp) on (M + dt C(x)) D = dt f (ViscousSolve.hpp; derivation and
// stopping rule in doc/formulation.md section 2.1).
#include "ViscousSolve.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/ElementKernel.hpp"
#include "../element/ViscousOperator.hpp"
#include "../parallel/Domain.hpp"
#include "../step/AwakeSet.hpp"

namespace qdem {

namespace {

// Enough for a condition number of M + dt C of ~1e7 at a tolerance of 1e-6
// (CG needs about sqrt(kappa)/2 ln(2/tol) iterations); beyond it the step
// is not worth solving this way and the user is told so.
constexpr int kMaxIterations = 5000;

bool viscous(const Settings& s, const Material& m) { return s.viscosityOn && m.viscosity > 0; }

}  // namespace

bool ViscousSolve::active() const {
    if (w_.settings.viscousIntegration != ViscousIntegration::Implicit || !w_.settings.viscosityOn) return false;
    // From the pieces, not this rank's tets: under MPI a rank may own none of
    // a viscous piece's tets, and every rank must take part in the solve's
    // reductions (the sleep decisions are the same on every rank).
    for (std::size_t p = 0; p < w_.pieces.size(); ++p)
        if (w_.sleeping.deformable(p) && w_.pieces[p].maxViscosity > 0) return true;
    return false;
}

template <class Fn>
void ViscousSolve::nodeLoop(Sum scope, int nSums, double* sums, Fn&& fn) {
    constexpr int kSums = 4;
    const int nth = layout_.nThreads;
    partial_.assign(static_cast<std::size_t>(kSums) * nth, 0.0);
    const AwakeNodes awake = awakeNodes();
    const int32_t count = awake.count;
#pragma omp parallel num_threads(nth)
    {
        double s[kSums] = {0, 0, 0, 0};
#pragma omp for schedule(static)
        for (int32_t i = 0; i < count; ++i) fn(awake[i], s);
        std::copy(s, s + kSums, partial_.data() + kSums * omp_get_thread_num());
    }
    for (int k = 0; k < nSums; ++k) {
        sums[k] = 0;
        for (int t = 0; t < nth; ++t) sums[k] += partial_[kSums * t + k];  // thread order: deterministic
    }
    if (Domain* dom = w_.domain.built(); dom && scope == Sum::Global && nSums > 0) dom->sumInRankOrder(sums, nSums);
}

ViscousSolve::AwakeNodes ViscousSolve::awakeNodes() const {
    const bool all = w_.sleeping.everything();
    const std::vector<int32_t>& ids = w_.sleeping.awakeNodes();
    return {all ? nullptr : ids.data(), static_cast<int32_t>(all ? w_.mass.size() : ids.size())};
}

void ViscousSolve::apply(double* p, double* y) {
    Domain* dom = w_.domain.built();
    if (dom) dom->forwardField(p);  // the ghosts' p, read by this rank's tets
    const ViscousStressOnly law;
    const AwakeNodes awake = awakeNodes();
    const int32_t count = awake.count;
#pragma omp parallel num_threads(layout_.nThreads)
    {
        const int th = omp_get_thread_num();
        AlignedVector<double>& buf = layout_.buffers[th];
        std::fill(buf.begin(), buf.end(), 0.0);
        const int32_t lo = layout_.nodeLo[th];
        BatchOut out;
        const TetBlock* blocks = blocks_[th].blocks.data();
        const double* X = w_.pos.data();
        // p holds 3 per node, as pos does (solve() sizes it)
        const auto last = static_cast<int32_t>(std::min(w_.pos.size() / 3, w_.mass.size())) - 1;
        for (const BlockSegment& sg : blocks_[th].segments) {
            const Material& m = w_.materials[sg.material];
            if (!viscous(w_.settings, m)) continue;
            const ElementParams prm{m.lambda(), m.mu(), m.beta()};
            const TetBlock* b = blocks + sg.first;
            for (int32_t e0 = sg.t0; e0 < sg.t1; e0 += kLanes, ++b) {
                const int cnt = sg.count(e0);
                elementBlock<ViscousStressOnly, true, false>(law, *b, X, p, last, prm, out);
                for (int l = 0; l < cnt; ++l)
                    for (int k = 0; k < 4; ++k) {
                        double* o = buf.data() + 3 * (b->node[k][l] - lo);
                        o[0] -= out.f[k][0][l];  // the kernel gives the force -C p
                        o[1] -= out.f[k][1][l];
                        o[2] -= out.f[k][2][l];
                    }
            }
        }
#pragma omp barrier
#pragma omp for schedule(static)
        for (int32_t i = 0; i < count; ++i) {
            const int32_t n = awake[i];
            layout_.sumNode(n, y + 3 * n);
        }
    }
    if (dom) dom->returnPartials(layout_, y);  // the other ranks' tets on this rank's nodes
}

void ViscousSolve::diagonal(double* diag) {
    const int32_t* conn = w_.tetNodes.data();
    const AwakeNodes awake = awakeNodes();
    const int32_t count = awake.count;
#pragma omp parallel num_threads(layout_.nThreads)
    {
        const int th = omp_get_thread_num();
        AlignedVector<double>& buf = layout_.buffers[th];
        std::fill(buf.begin(), buf.end(), 0.0);
        const int32_t lo = layout_.nodeLo[th];
        const double* X = w_.pos.data();
        for (const TetSegment& sg : layout_.share[th]) {
            for (int32_t e = sg.t0; e < sg.t1; ++e) {
                const Material& m = w_.materials[w_.tetMaterial[e]];
                if (!viscous(w_.settings, m)) continue;
                const ElementParams prm{m.lambda(), m.mu(), m.beta()};
                const int32_t* c = conn + 4 * e;
                const Mat3 B = loadRowMajor(w_.tetB.data() + 9 * e);
                const Mat3 F = edgeMatrix(X + 3 * c[0], X + 3 * c[1], X + 3 * c[2], X + 3 * c[3]) * B;
                double d[4][3];
                viscousDiagonal(F, B, w_.tetVol0[e], prm, d);
                for (int k = 0; k < 4; ++k)
                    for (int i = 0; i < 3; ++i) buf[3 * (c[k] - lo) + i] += d[k][i];
            }
        }
#pragma omp barrier
#pragma omp for schedule(static)
        for (int32_t i = 0; i < count; ++i) {
            const int32_t n = awake[i];
            layout_.sumNode(n, diag + 3 * n);
        }
    }
    if (Domain* dom = w_.domain.built()) dom->returnPartials(layout_, diag);
}

ViscousSolve::Vectors ViscousSolve::vectors() {
    return {w_.mass.data(), w_.blocked.data(), x_.data(), r_.data(), z_.data(), p_.data(), cp_.data(), q_.data(),
            diag_.data()};
}

bool ViscousSolve::start(double dt, const double* f, double* s) {
    const auto [M, blk, X, R, Z, P, CP, Q, D] = vectors();
    // The last step's D, when it was the last step's (not after a pause of
    // the solve, e.g. while every viscous piece slept); scaled to this dt,
    // since D ~ dt a.
    if (warm_.size() != x_.size()) warm_.assign(x_.size(), 0.0), warmIter = -1;
    bool warm = w_.settings.viscousWarmStart && warmIter >= 0 && warmIter + 1 == w_.iter && warmDt > 0;
    if (warm) {
        const double* W = warm_.data();
        const double scale = dt / warmDt;
        nodeLoop(Sum::Local, 0, s, [&](int32_t n, double*) {
            for (int d = 0; d < 3; ++d) X[3 * n + d] = ((blk[n] >> d) & 1u) ? 0.0 : scale * W[3 * n + d];
        });
        apply(X, CP);  // C x0: one operator application
    }
    // r = dt f - (M + dt C) x0, and the sums; bMb = ||dt f||_{M^-1}^2 is
    // what the residual is from D = 0.
    nodeLoop(Sum::Global, 4, s, [&](int32_t n, double* acc) {
        for (int d = 0; d < 3; ++d) {
            const int32_t k = 3 * n + d;
            D[k] = M[n] + dt * D[k];
            if (!warm) X[k] = 0;
            Q[k] = warm ? CP[k] : 0.0;  // q = C x, on every DOF as in the iterations
            if ((blk[n] >> d) & 1u) {
                R[k] = Z[k] = P[k] = 0;
                continue;
            }
            const double b = dt * f[k];
            R[k] = warm ? b - M[n] * X[k] - dt * CP[k] : b;
            Z[k] = R[k] / D[k];
            P[k] = Z[k];
            acc[0] += R[k] * Z[k];
            acc[1] += R[k] * R[k] / M[n];
            acc[2] += M[n] * X[k] * X[k];
            acc[3] += b * b / M[n];
        }
    });
    if (warm && !(s[1] < s[3])) {
        // The guess is no closer than D = 0 (a contact began or ended, a jolt):
        // start from 0.  The same decision on every rank (global sums).
        warm = false;
        nodeLoop(Sum::Global, 2, s, [&](int32_t n, double* acc) {
            for (int d = 0; d < 3; ++d) {
                const int32_t k = 3 * n + d;
                X[k] = Q[k] = 0;
                if ((blk[n] >> d) & 1u) continue;
                R[k] = dt * f[k];
                Z[k] = R[k] / D[k];
                P[k] = Z[k];
                acc[0] += R[k] * Z[k];
                acc[1] += R[k] * R[k] / M[n];
            }
        });
        s[2] = 0;
    }
    return warm;
}

double ViscousSolve::precondition(bool setP) {
    const auto [M, blk, X, R, Z, P, CP, Q, D] = vectors();
    precond_.apply(R, Z);  // (R is 0 on blocked DOFs)
    double s[4];
    // Zeroed on the blocked DOFs: Pi A^-1 Pi, symmetric positive definite on
    // the free DOFs, as the conjugate gradients need.
    nodeLoop(Sum::Global, 1, s, [&](int32_t n, double* acc) {
        for (int d = 0; d < 3; ++d) {
            const int32_t k = 3 * n + d;
            if ((blk[n] >> d) & 1u) {
                Z[k] = 0;
                continue;
            }
            acc[0] += R[k] * Z[k];
            if (setP) P[k] = Z[k];
        }
    });
    return s[0];
}

void ViscousSolve::keep(double dt) {
    // Nodes not solved for (asleep, or other ranks') start from 0 when they
    // are next: a piece that wakes has no last change.
    if (!w_.sleeping.everything()) std::fill(warm_.begin(), warm_.end(), 0.0);
    double* W = warm_.data();
    const double* X = x_.data();
    nodeLoop(Sum::Local, 0, nullptr, [&](int32_t n, double*) {
        for (int d = 0; d < 3; ++d) W[3 * n + d] = X[3 * n + d];  // (0 on blocked DOFs)
    });
    warmIter = w_.iter;
    warmDt = dt;
}

const double* ViscousSolve::solve(double dt, const double* f) {
    const double t0 = omp_get_wtime();
    const int nth = omp_get_max_threads();
    if (!layout_.matches(nth, w_.sleeping.version())) {
        layout_.build(w_.tetNodes.data(), w_.sleeping.awakeTets(), nth, w_.sleeping.version());
        buildThreadBlocks(layout_, w_.tetNodes.data(), w_.tetB.data(), w_.tetVol0.data(), w_.tetMaterial.data(), blocks_);
    }
    const std::size_t n3 = 3 * w_.mass.size();
    for (auto* v : {&x_, &r_, &z_, &p_, &cp_, &q_, &diag_, &delta_})
        if (v->size() != n3) v->assign(n3, 0.0);
    const auto [M, blk, X, R, Z, P, CP, Q, D] = vectors();
    const double tol2 = w_.settings.viscousTolerance * w_.settings.viscousTolerance;

    // Jacobi preconditioner: the diagonal of M + dt C on the current shape.
    // With the Cholesky one, Jacobi's is left to the pieces it does not cover,
    // those without viscosity: there C = 0 and the diagonal is M.
    if (cholesky()) {
        precond_.prepare(dt);
        nodeLoop(Sum::Local, 0, nullptr, [&](int32_t n, double*) { D[3 * n] = D[3 * n + 1] = D[3 * n + 2] = 0; });
    } else {
        diagonal(D);
    }
    double s[4];
    startedWarm = start(dt, f, s);
    double rz = s[0], rMr = s[1], xMx = s[2];
    // (start() left Jacobi's Z; not needed when the warm start is close enough)
    if (cholesky() && rMr > tol2 * xMx) rz = precondition(true);
    iterations = 0;
    // Stop when ||r||_{M^-1} <= tol ||D||_M: the velocity change's error is
    // then at most tol times the change (doc/formulation.md 2.1).  From a
    // warm start that may hold before the first iteration.
    while (rMr > tol2 * xMx) {
        if (iterations == kMaxIterations)
            throw StabilityError(cat("QDEM: the implicit viscous solve did not converge in ", kMaxIterations,
                                     " iterations at step ", w_.iter, " (relative error bound ",
                                     std::sqrt(rMr) / std::sqrt(std::max(xMx, 1e-300)), ", asked ",
                                     w_.settings.viscousTolerance,
                                     "): raise QdemEngine.viscousTolerance, lower O.dt, or use "
                                     "viscousIntegration='explicit'."));
        apply(P, CP);
        nodeLoop(Sum::Global, 1, s, [&](int32_t n, double* acc) {
            for (int d = 0; d < 3; ++d) {
                const int32_t k = 3 * n + d;
                if (!((blk[n] >> d) & 1u)) acc[0] += P[k] * (M[n] * P[k] + dt * CP[k]);
            }
        });
        const double pAp = s[0];
        if (!(pAp > 0) || !std::isfinite(pAp))
            throw StabilityError(cat("QDEM: the implicit viscous solve broke down at step ", w_.iter,
                                     " (p.Ap = ", pAp, "): positions or velocities are not finite; lower O.dt."));
        const double alpha = rz / pAp;
        nodeLoop(Sum::Global, 3, s, [&](int32_t n, double* acc) {
            for (int d = 0; d < 3; ++d) {
                const int32_t k = 3 * n + d;
                Q[k] += alpha * CP[k];  // every DOF: the viscous force on blocked ones too
                if ((blk[n] >> d) & 1u) continue;
                X[k] += alpha * P[k];
                R[k] -= alpha * (M[n] * P[k] + dt * CP[k]);
                Z[k] = R[k] / D[k];
                acc[0] += R[k] * Z[k];
                acc[1] += R[k] * R[k] / M[n];
                acc[2] += M[n] * X[k] * X[k];
            }
        });
        ++iterations;
        rMr = s[1], xMx = s[2];
        if (rMr <= tol2 * xMx) break;
        if (cholesky()) s[0] = precondition(false);
        const double beta = s[0] / rz;
        rz = s[0];
        nodeLoop(Sum::Global, 0, s, [&](int32_t n, double*) {
            for (int d = 0; d < 3; ++d) {
                const int32_t k = 3 * n + d;
                if (!((blk[n] >> d) & 1u)) P[k] = Z[k] + beta * P[k];
            }
        });
    }
    keep(dt);
    totalIterations += iterations;
    seconds = omp_get_wtime() - t0;
    return Q;
}

double ViscousSolve::dissipation(double dt, const double* vNew) {
    const double t0 = omp_get_wtime();
    // The applied viscous force is -g, g = C v_old + q = C(v_old + D), with
    // v_old + D the velocity the solve converged to (v_{n+1/2} within its
    // residual).  Booked: dt g.v_{n+1/2} (= dt v_{n+1/2}.C v_{n+1/2} >= 0 when
    // converged, the mirror of the explicit dt v_{n-1/2}.C v_{n-1/2};
    // doc/formulation.md 2.1).  The element phase booked dt v_old.C v_old;
    // what is left is dt (v_old.C delta + q.v_new), delta = v_new - v_old.
    double* CD = cp_.data();
    apply(delta_.data(), CD);
    const double* Q = q_.data();
    const double* Dl = delta_.data();
    double s[4];
    // This rank's share: the ledger is summed over the ranks at the step's end.
    nodeLoop(Sum::Local, 1, s, [&](int32_t n, double* acc) {
        for (int d = 0; d < 3; ++d) {
            const int32_t k = 3 * n + d;
            acc[0] += (vNew[k] - Dl[k]) * CD[k] + Q[k] * vNew[k];
        }
    });
    seconds += omp_get_wtime() - t0;
    return dt * s[0];
}

}  // namespace qdem
