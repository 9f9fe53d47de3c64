// The co-rotated reference-shape Cholesky preconditioner (CorotatedCholesky.hpp).
#include "CorotatedCholesky.hpp"

#include <omp.h>

#include <Eigen/LU>  // determinant()
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/ViscousOperator.hpp"
#include "../parallel/Domain.hpp"
#include "../step/AwakeSet.hpp"

namespace qdem {

namespace {

// Within this relative change of the step the last factor is kept: it is a
// preconditioner (the answer is set by the solve's tolerance), and a run whose
// step drifts slowly would otherwise refactor at every step.
constexpr double kDtSlack = 1e-2;

}  // namespace

CorotatedCholesky::Key CorotatedCholesky::keyOf(const PieceInfo& pc, double dt) const {
    const Material& m = w_.materials[pc.material];
    Key k;
    k.dt = dt;
    k.lambda = m.lambda(), k.mu = m.mu(), k.beta = m.beta();
    for (int32_t n = pc.nodeBegin; n < pc.nodeEnd; ++n) k.massSum += w_.mass[n];
    for (int32_t e = pc.tetBegin; e < pc.tetEnd; ++e) k.volSum += w_.tetVol0[e];
    k.nodeBegin = pc.nodeBegin, k.nodeEnd = pc.nodeEnd, k.tetBegin = pc.tetBegin, k.tetEnd = pc.tetEnd;
    return k;
}

bool CorotatedCholesky::sameKey(const Key& a, const Key& b) {
    return std::abs(a.dt - b.dt) <= kDtSlack * b.dt && a.lambda == b.lambda && a.mu == b.mu && a.beta == b.beta &&
           a.massSum == b.massSum && a.volSum == b.volSum && a.nodeBegin == b.nodeBegin && a.nodeEnd == b.nodeEnd &&
           a.tetBegin == b.tetBegin && a.tetEnd == b.tetEnd;
}

void CorotatedCholesky::factor(int32_t piece, const Key& key) {
    const PieceInfo& pc = w_.pieces[piece];
    const int32_t nb = pc.nodeBegin, n = 3 * (pc.nodeEnd - pc.nodeBegin);
    // A_ref = M + dt C_ref, lower triangle (the factorization reads that).
    std::vector<Eigen::Triplet<double, int>> t;
    t.reserve(static_cast<std::size_t>(78) * (pc.tetEnd - pc.tetBegin) + n);
    for (int32_t i = 0; i < n; ++i) t.emplace_back(i, i, w_.mass[nb + i / 3]);
    double K[12][12];
    for (int32_t e = pc.tetBegin; e < pc.tetEnd; ++e) {
        const Material& mat = w_.materials[w_.tetMaterial[e]];  // each element its own C
        const ElementParams prm{mat.lambda(), mat.mu(), mat.viscosity > 0 ? mat.beta() : 0.0};
        const int32_t* c = w_.tetNodes.data() + 4 * e;
        viscousReferenceMatrix(loadRowMajor(w_.tetB.data() + 9 * e), w_.tetVol0[e], prm, K);
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) {
                        const int r = 3 * (c[a] - nb) + i, s = 3 * (c[b] - nb) + j;
                        if (s <= r) t.emplace_back(r, s, key.dt * K[3 * a + i][3 * b + j]);
                    }
    }
    Eigen::SparseMatrix<double> A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> llt(A);
    if (llt.info() != Eigen::Success)
        throw StabilityError(cat("QDEM: piece ", piece, ": M + dt C of its reference shape is not positive definite ",
                                 "(a node without mass?); use viscousPreconditioner='jacobi'."));
    const Eigen::SparseMatrix<double>& L = llt.matrixL().nestedExpression();
    Factor& f = factors_[piece];
    f.colStart.assign(L.outerIndexPtr(), L.outerIndexPtr() + n + 1);
    f.row.assign(L.innerIndexPtr(), L.innerIndexPtr() + L.nonZeros());
    f.val.assign(L.valuePtr(), L.valuePtr() + L.nonZeros());
    f.perm.assign(llt.permutationP().indices().data(), llt.permutationP().indices().data() + n);
    for (int32_t j = 0; j < n; ++j)
        if (f.row[f.colStart[j]] != j) throw std::logic_error("CorotatedCholesky: diagonal not first in L");
    f.key = key;
    f.valid = true;
}

void CorotatedCholesky::rotation(Task& t, const double* x) const {
    const PieceInfo& pc = w_.pieces[t.piece];
    const int32_t nb = pc.nodeBegin, nn = pc.nodeEnd - pc.nodeBegin;
    const double* X = w_.refPos.data() + 3 * nb;
    const double* m = w_.mass.data() + nb;
    double ms = 0, c[3] = {0, 0, 0}, C[3] = {0, 0, 0};
    for (int32_t i = 0; i < nn; ++i) {
        ms += m[i];
        for (int d = 0; d < 3; ++d) c[d] += m[i] * x[3 * i + d], C[d] += m[i] * X[3 * i + d];
    }
    for (int d = 0; d < 3; ++d) c[d] /= ms, C[d] /= ms;
    Mat3 A = Mat3::Zero();
    for (int32_t i = 0; i < nn; ++i) {
        const Vec3 u(x[3 * i] - c[0], x[3 * i + 1] - c[1], x[3 * i + 2] - c[2]);
        const Vec3 U(X[3 * i] - C[0], X[3 * i + 1] - C[1], X[3 * i + 2] - C[2]);
        A.noalias() += m[i] * u * U.transpose();
    }
    // The polar factor of A: the rotation R minimizing sum m |R (X - C) - (x - c)|^2.
    Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 U = svd.matrixU();
    if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) *= -1;
    const Mat3 R = U * svd.matrixV().transpose();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t.R[3 * i + j] = R(i, j);
}

void CorotatedCholesky::prepare(double dt) {
    const double t0 = omp_get_wtime();
    Domain* dom = w_.domain.built();
    const std::size_t np = w_.pieces.size();
    if (factors_.size() != np) factors_.assign(np, Factor{});
    tasks_.clear();
    splitPieces_.clear();
    splitOffset_.clear();
    int32_t off = 0, maxNodes = 0;
    for (std::size_t p = 0; p < np; ++p) {
        const PieceInfo& pc = w_.pieces[p];
        if (!w_.sleeping.deformable(p) || !w_.settings.viscosityOn || !(pc.maxViscosity > 0)) continue;
        const auto piece = static_cast<int32_t>(p);
        maxNodes = std::max(maxNodes, pc.nodeEnd - pc.nodeBegin);
        if (!dom) {
            tasks_.push_back({piece, -1, {}});
            continue;
        }
        // The owners are alike on every rank (Partition.hpp): so is the split list.
        const std::vector<int32_t>& owner = dom->partition().nodeOwner;
        const int first = owner[pc.nodeBegin];
        bool split = false, mine = false;
        for (int32_t n = pc.nodeBegin; n < pc.nodeEnd; ++n) {
            split |= owner[n] != first;
            mine |= owner[n] == dom->rank();
        }
        if (split) {
            splitPieces_.push_back(piece);
            splitOffset_.push_back(off);
            if (mine) tasks_.push_back({piece, off, {}});
            off += 3 * (pc.nodeEnd - pc.nodeBegin);
        } else if (mine) {
            tasks_.push_back({piece, -1, {}});
        }
    }
    // Factors whose key changed (each piece's its own work: any thread).
    std::vector<std::pair<int32_t, Key>> todo;
    for (const Task& t : tasks_) {
        const Key k = keyOf(w_.pieces[t.piece], dt);
        const Factor& f = factors_[t.piece];
        if (!f.valid || !sameKey(k, f.key)) todo.emplace_back(t.piece, k);
    }
    if (!todo.empty()) {
        std::string error;
#pragma omp parallel for schedule(dynamic, 1)
        for (std::size_t i = 0; i < todo.size(); ++i) {
            try {
                factor(todo[i].first, todo[i].second);
            } catch (const std::exception& e) {
#pragma omp critical(qdemViscousFactor)
                if (error.empty()) error = e.what();
            }
        }
        if (!error.empty()) throw StabilityError(error);
        factorizations += static_cast<long>(todo.size());
    }
    const int nth = omp_get_max_threads();
    if (static_cast<int>(scratch_.size()) < nth) scratch_.resize(nth);
    for (auto& s : scratch_)
        if (s.size() < static_cast<std::size_t>(3 * maxNodes)) s.assign(3 * maxNodes, 0.0);
    // The split pieces' positions: each entry from its owner alone.
    gather_.assign(off, 0.0);
    if (off > 0) {
        for (std::size_t k = 0; k < splitPieces_.size(); ++k) {
            const PieceInfo& pc = w_.pieces[splitPieces_[k]];
            for (int32_t n = pc.nodeBegin; n < pc.nodeEnd; ++n)
                if (dom->owns(n))
                    for (int d = 0; d < 3; ++d) gather_[splitOffset_[k] + 3 * (n - pc.nodeBegin) + d] = w_.pos[3 * n + d];
        }
        dom->sumInRankOrder(gather_.data(), off);
    }
    for (Task& t : tasks_)
        rotation(t, t.gatherOffset < 0 ? w_.pos.data() + 3 * w_.pieces[t.piece].nodeBegin : gather_.data() + t.gatherOffset);
    factorSeconds = omp_get_wtime() - t0;
}

void CorotatedCholesky::solvePiece(const Task& t, const double* r, double* z, std::vector<double>& y) const {
    const PieceInfo& pc = w_.pieces[t.piece];
    const Factor& f = factors_[t.piece];
    const int32_t nb = pc.nodeBegin, nn = pc.nodeEnd - pc.nodeBegin, n = 3 * nn;
    const double* R = t.R;
    const int32_t* perm = f.perm.data();
    // y = P R^T r
    for (int32_t i = 0; i < nn; ++i) {
        const double* ri = r + 3 * i;
        for (int d = 0; d < 3; ++d)
            y[perm[3 * i + d]] = R[d] * ri[0] + R[3 + d] * ri[1] + R[6 + d] * ri[2];
    }
    const int32_t* cs = f.colStart.data();
    const int32_t* row = f.row.data();
    const double* val = f.val.data();
    // L y' = y, then L^T y'' = y'
    for (int32_t j = 0; j < n; ++j) {
        const double yj = (y[j] /= val[cs[j]]);
        for (int32_t p = cs[j] + 1; p < cs[j + 1]; ++p) y[row[p]] -= val[p] * yj;
    }
    for (int32_t j = n - 1; j >= 0; --j) {
        double s = y[j];
        for (int32_t p = cs[j] + 1; p < cs[j + 1]; ++p) s -= val[p] * y[row[p]];
        y[j] = s / val[cs[j]];
    }
    // z = R P^T y, on this rank's nodes
    Domain* dom = t.gatherOffset < 0 ? nullptr : w_.domain.built();
    for (int32_t i = 0; i < nn; ++i) {
        if (dom && !dom->owns(nb + i)) continue;
        const double a = y[perm[3 * i]], b = y[perm[3 * i + 1]], c = y[perm[3 * i + 2]];
        double* zi = z + 3 * (nb + i);
        for (int d = 0; d < 3; ++d) zi[d] = R[3 * d] * a + R[3 * d + 1] * b + R[3 * d + 2] * c;
    }
}

void CorotatedCholesky::apply(const double* r, double* z) {
    if (!gather_.empty()) {
        Domain* dom = w_.domain.built();
        std::fill(gather_.begin(), gather_.end(), 0.0);
        for (std::size_t k = 0; k < splitPieces_.size(); ++k) {
            const PieceInfo& pc = w_.pieces[splitPieces_[k]];
            for (int32_t n = pc.nodeBegin; n < pc.nodeEnd; ++n)
                if (dom->owns(n))
                    for (int d = 0; d < 3; ++d) gather_[splitOffset_[k] + 3 * (n - pc.nodeBegin) + d] = r[3 * n + d];
        }
        dom->sumInRankOrder(gather_.data(), static_cast<int>(gather_.size()));
    }
    const auto nt = static_cast<int32_t>(tasks_.size());
#pragma omp parallel num_threads(std::min<int>(omp_get_max_threads(), std::max<int32_t>(nt, 1)))
    {
        std::vector<double>& y = scratch_[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 1)
        for (int32_t k = 0; k < nt; ++k) {
            const Task& t = tasks_[k];
            const double* src =
                t.gatherOffset < 0 ? r + 3 * w_.pieces[t.piece].nodeBegin : gather_.data() + t.gatherOffset;
            solvePiece(t, src, z, y);
        }
    }
}

}  // namespace qdem
