// Rigid pieces (RigidBodies.hpp): a leapfrog for the centre (the nodes'
// scheme) and, for the orientation, the angular momentum L advanced by the
// torque at half steps and the rotation by the angular velocity at the half
// step, w = R_h I^-1 R_h^T L (the implicit midpoint rule, solved by a few
// fixed-point passes): L is exactly conserved without torque, and the scheme
// is time-reversible, so the energy of a free tumbling body stays bounded.
#include "RigidBodies.hpp"

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "../core/Errors.hpp"
#include "../step/WorldState.hpp"

namespace qdem {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using RowMap = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
using ConstRowMap = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;

// The rotation by the vector theta (angle |theta| about its direction).
Eigen::Quaterniond rotation(const Vec3& theta) {
    const double a = theta.norm();
    if (a < 1e-300) return Eigen::Quaterniond::Identity();
    return Eigen::Quaterniond(Eigen::AngleAxisd(a, theta / a));
}

constexpr int kFixedPointPasses = 4;  // |dt w| << 1: each pass gains that factor

// The rigid motion that fits nodes [b, e) best in the mass-weighted least
// squares sense: centre c, its velocity V, angular momentum L about c and
// angular velocity w = I^-1 L (doc/formulation.md, "Adaptive rigidity").
struct RigidFit {
    double m = 0;
    Vec3 c, V, L, w;
    Mat3 Iinv;
};

RigidFit fitRigidMotion(const double* x, const double* v, const double* mass, int32_t b, int32_t e) {
    RigidFit f;
    Vec3 c = Vec3::Zero(), mv = Vec3::Zero();
    for (int32_t n = b; n < e; ++n) {
        f.m += mass[n];
        c += mass[n] * Vec3(x[3 * n], x[3 * n + 1], x[3 * n + 2]);
        mv += mass[n] * Vec3(v[3 * n], v[3 * n + 1], v[3 * n + 2]);
    }
    f.c = c / f.m;
    f.V = mv / f.m;
    Mat3 I = Mat3::Zero();
    f.L = Vec3::Zero();
    for (int32_t n = b; n < e; ++n) {
        const Vec3 r = Vec3(x[3 * n], x[3 * n + 1], x[3 * n + 2]) - f.c;
        I += mass[n] * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
        f.L += mass[n] * r.cross(Vec3(v[3 * n], v[3 * n + 1], v[3 * n + 2]) - f.V);
    }
    f.Iinv = I.inverse();
    f.w = f.Iinv * f.L;
    return f;
}

// The load over the strain it makes, 2 E A (doc/formulation.md, "Adaptive
// rigidity"): a bar of section A loaded by +-P at its ends strains by
// P / (E A) while its nodes' loads sum to 2P in magnitude.  A = V / l, the
// piece's volume over its largest reference extent (the section of the bar
// of its volume along its length); E the softest of its elements' moduli
// (the larger strain).
double wakeStiffness(const PieceInfo& P, const double* ref, const Column<int32_t>& tetMaterial,
                     const std::vector<Material>& materials) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
        const Vec3 x(ref[3 * n], ref[3 * n + 1], ref[3 * n + 2]);
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
    }
    double young = std::numeric_limits<double>::infinity();
    for (int32_t t = P.tetBegin; t < P.tetEnd; ++t) young = std::min(young, materials[tetMaterial[t]].young);
    const double extent = (hi - lo).maxCoeff();
    return extent > 0 && std::isfinite(young) ? 2 * young * P.volume / extent : 0.0;
}

}  // namespace

void RigidBodies::piecesAdded() {
    const std::size_t np = w_.pieces.size(), n3 = 3 * w_.mass.size();
    body_.resize(kBody * np, 0.0);
    offset_.resize(n3, 0.0);
    load0_.resize(n3, 0.0);
    loadSet_.resize(np, 0);
    belowFor_.resize(np, 0.0);
    rate_.resize(np, 0.0);
    loadChange_.resize(np, 0.0);
    loadStrain_.resize(np, 0.0);
    wake_.resize(np, 0);
    const std::size_t known = minEdge_.size();
    minEdge_.resize(np, 0.0);
    wakeStiffness_.resize(np, 0.0);
    for (std::size_t p = known; p < np; ++p) {
        wakeStiffness_[p] = wakeStiffness(w_.pieces[p], w_.refPos.data(), w_.tetMaterial, w_.materials);
        double e2 = std::numeric_limits<double>::infinity();
        for (int32_t t = w_.pieces[p].tetBegin; t < w_.pieces[p].tetEnd; ++t)
            for (int i = 0; i < 4; ++i)
                for (int j = i + 1; j < 4; ++j) {
                    const double* a = &w_.refPos[3 * w_.tetNodes[4 * t + i]];
                    const double* b = &w_.refPos[3 * w_.tetNodes[4 * t + j]];
                    e2 = std::min(e2, (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                          (a[2] - b[2]) * (a[2] - b[2]));
                }
        minEdge_[p] = std::sqrt(e2);
    }
}

// The rigid state from the nodes: centre, momentum, angular momentum and
// inertia; the node velocities projected on the rigid motions (the
// mass-weighted least-squares fit: what is removed is orthogonal to it, so
// its kinetic energy is the difference, booked in energy.rigid).  The
// positions stay as they are: the current shape is the body's.
void RigidBodies::start(std::size_t p, double& removed) {
    const PieceInfo& P = w_.pieces[p];
    const double* x = w_.pos.data();
    double* v = w_.vel.data();
    const RigidFit fit = fitRigidMotion(x, v, w_.mass.data(), P.nodeBegin, P.nodeEnd);
    const double m = fit.m;
    const Vec3 &c = fit.c, &V = fit.V, &L = fit.L, &w = fit.w;
    const Mat3& Iinv = fit.Iinv;
    double ek = 0;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
        const Vec3 r = Vec3(x[3 * n], x[3 * n + 1], x[3 * n + 2]) - c;
        const Vec3 vr = V + w.cross(r);
        for (int d = 0; d < 3; ++d) {
            ek += 0.5 * w_.mass[n] * (v[3 * n + d] - vr[d]) * (v[3 * n + d] - vr[d]);
            v[3 * n + d] = vr[d];
            offset_[3 * n + d] = r[d];  // body frame = world frame now (q = 1)
        }
    }
    removed = ek;
    double* b = &body_[kBody * p];
    for (int d = 0; d < 3; ++d) b[kX + d] = c[d], b[kV + d] = V[d], b[kL + d] = L[d];
    b[kQ] = 1, b[kQ + 1] = b[kQ + 2] = b[kQ + 3] = 0;
    RowMap(b + kIInv) = Iinv;
    b[kMass] = m;
    b[kScale] = 0;
    b[kOn] = 1;
    loadSet_[p] = 0;
    loadChange_[p] = 0;
    loadStrain_[p] = 0;
    wake_[p] = 0;
}

void RigidBodies::sumForces(std::size_t p, const double* b, double* F, double* T, StepSums& s) const {
    const PieceInfo& P = w_.pieces[p];
    const double* x = w_.pos.data();
    const double* v = w_.vel.data();
    const double* fx = w_.extForce.data();
    const double* fc = w_.contacts.active ? w_.contacts.force.data() : nullptr;
    double* out = w_.force.data();
    const double g[3] = {w_.gravity[0], w_.gravity[1], w_.gravity[2]};
    for (int d = 0; d < 3; ++d) F[d] = T[d] = 0;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
        double f[3];
        for (int d = 0; d < 3; ++d) {
            f[d] = fx[3 * n + d] + w_.mass[n] * g[d] + (fc ? fc[3 * n + d] : 0.0);
            out[3 * n + d] = f[d];
            F[d] += f[d];
            s.gravity -= w_.mass[n] * g[d] * v[3 * n + d];  // (times dt by the caller)
            s.boundary -= fx[3 * n + d] * v[3 * n + d];
        }
        const double r[3] = {x[3 * n] - b[kX], x[3 * n + 1] - b[kX + 1], x[3 * n + 2] - b[kX + 2]};
        T[0] += r[1] * f[2] - r[2] * f[1];
        T[1] += r[2] * f[0] - r[0] * f[2];
        T[2] += r[0] * f[1] - r[1] * f[0];
    }
}

// The load that deforms the piece: each node's force less its mass times
// its rigid acceleration (d_i = f_i - m_i (A + alpha x r + w x (w x r)),
// self-equilibrated), in the body frame.  The first rigid step records it;
// later steps compare (sum over nodes of |d_i - d0_i|, over the scale
// max(sum |d0_i|, weight)).
void RigidBodies::wakeTest(std::size_t p, const double* b, const Mat3& R, const Vec3& w, const double* F,
                           const double* T) {
    const PieceInfo& P = w_.pieces[p];
    const double m = b[kMass];
    const Mat3 IwInv = R * ConstRowMap(b + kIInv) * R.transpose();
    const Vec3 L(b[kL], b[kL + 1], b[kL + 2]);
    const Vec3 A = Vec3(F[0], F[1], F[2]) / m;
    const Vec3 alpha = IwInv * (Vec3(T[0], T[1], T[2]) - w.cross(L));
    const bool record = !loadSet_[p];
    double sum = 0;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
        const Vec3 r = Vec3(w_.pos[3 * n] - b[kX], w_.pos[3 * n + 1] - b[kX + 1], w_.pos[3 * n + 2] - b[kX + 2]);
        const Vec3 a = A + alpha.cross(r) + w.cross(w.cross(r));
        const Vec3 d = R.transpose() * (Vec3(w_.force[3 * n], w_.force[3 * n + 1], w_.force[3 * n + 2]) -
                                        w_.mass[n] * a);
        double* d0 = &load0_[3 * n];
        if (record) {
            for (int k = 0; k < 3; ++k) d0[k] = d[k];
            sum += d.norm();
        } else {
            sum += (d - Vec3(d0[0], d0[1], d0[2])).norm();
        }
    }
    double* bw = &body_[kBody * p];
    if (record) {
        bw[kScale] = std::max(sum, m * w_.gravity.norm());
        loadSet_[p] = 1;
        loadChange_[p] = 0;
        loadStrain_[p] = 0;
        return;
    }
    loadChange_[p] = bw[kScale] > 0 ? sum / bw[kScale] : (sum > 0 ? std::numeric_limits<double>::infinity() : 0.0);
    // Both: a large change for the load it carries, and one that strains it
    // (a piece rocking on its support shifts its weight, a large relative
    // change that hardly strains it).
    loadStrain_[p] = wakeStiffness_[p] > 0 ? sum / wakeStiffness_[p] : std::numeric_limits<double>::infinity();
    if (loadChange_[p] > w_.settings.rigidWakeLoad && loadStrain_[p] > w_.settings.rigidWakeStrain) wake_[p] = 1;
}

void RigidBodies::forgetStale() {
    for (std::size_t p = 0; p < w_.pieces.size(); ++p)
        if (body_[kBody * p + kOn] != 0 && !w_.sleeping.rigid(p)) {
            body_[kBody * p + kOn] = 0;
            belowFor_[p] = 0;
            wake_[p] = 0;
        }
}

RigidBodies::StepSums RigidBodies::advance(double dt, double* speed2) {
    const std::vector<int32_t>& rig = w_.sleeping.rigidPieces();
    const auto nr = static_cast<int32_t>(rig.size());
    sums_.assign(nr, StepSums{});
    std::vector<double> removed(nr, 0.0);
#pragma omp parallel for schedule(dynamic, 1)
    for (int32_t k = 0; k < nr; ++k) {
        const auto p = static_cast<std::size_t>(rig[k]);
        if (body_[kBody * p + kOn] == 0) start(p, removed[k]);
        double* b = &body_[kBody * p];
        StepSums& s = sums_[k];
        double F[3], T[3];
        sumForces(p, b, F, T, s);
        s.gravity *= dt;
        s.boundary *= dt;
        const double m = b[kMass];
        const ConstRowMap Iinv(b + kIInv);
        const Eigen::Quaterniond q(b[kQ], b[kQ + 1], b[kQ + 2], b[kQ + 3]);
        const Mat3 R = q.toRotationMatrix();
        const Vec3 Lold(b[kL], b[kL + 1], b[kL + 2]), Vold(b[kV], b[kV + 1], b[kV + 2]);
        wakeTest(p, b, R, R * (Iinv * (R.transpose() * Lold)), F, T);
        const Vec3 Vnew = Vold + dt / m * Vec3(F[0], F[1], F[2]);
        const Vec3 Lnew = Lold + dt * Vec3(T[0], T[1], T[2]);
        // The angular velocity at the half step, w = R_h I^-1 R_h^T L, R_h = rot(dt/2 w) R.
        Vec3 w = R * (Iinv * (R.transpose() * Lnew));
        Mat3 Rh = R;
        for (int it = 0; it < kFixedPointPasses; ++it) {
            Rh = (rotation(0.5 * dt * w) * q).normalized().toRotationMatrix();
            w = Rh * (Iinv * (Rh.transpose() * Lnew));
        }
        const Eigen::Quaterniond qNew = (rotation(dt * w) * q).normalized();
        const Mat3 Rnew = qNew.toRotationMatrix();
        const Vec3 xNew = Vec3(b[kX], b[kX + 1], b[kX + 2]) + dt * Vnew;
        // Kinetic energy at the integer time level, as the nodes' (the mean of the half steps).
        const Vec3 vm = 0.5 * (Vold + Vnew), Lm = 0.5 * (Lold + Lnew);
        s.kinetic = 0.5 * m * vm.squaredNorm() + 0.5 * Lm.dot(R * (Iinv * (R.transpose() * Lm)));
        // The nodes: positions at the new step, velocities at the half step
        // (so that a switch back to deformable goes on from them with no jump).
        const PieceInfo& P = w_.pieces[p];
        double sp2 = 0, finite = 0;
        for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
            const Vec3 o(offset_[3 * n], offset_[3 * n + 1], offset_[3 * n + 2]);
            const Vec3 xn = xNew + Rnew * o, vn = Vnew + w.cross(Rh * o);
            for (int d = 0; d < 3; ++d) w_.pos[3 * n + d] = xn[d], w_.vel[3 * n + d] = vn[d];
            sp2 = std::max(sp2, vn.squaredNorm());
            finite += xn.sum() + vn.sum();
        }
        if (speed2) speed2[p] = sp2;
        s.finite = std::isfinite(finite);
        for (int d = 0; d < 3; ++d) b[kX + d] = xNew[d], b[kV + d] = Vnew[d], b[kL + d] = Lnew[d];
        b[kQ] = qNew.w(), b[kQ + 1] = qNew.x(), b[kQ + 2] = qNew.y(), b[kQ + 3] = qNew.z();
    }
    StepSums total;
    double gone = 0;
    for (int32_t k = 0; k < nr; ++k) {  // in piece order: the same bits at any thread count
        total.kinetic += sums_[k].kinetic;
        total.gravity += sums_[k].gravity;
        total.boundary += sums_[k].boundary;
        total.finite = total.finite && sums_[k].finite;
        gone += removed[k];
    }
    if (w_.settings.trackEnergy) w_.energy.rigid += gone;
    return total;
}

void RigidBodies::measure(double dt) {
    if (!w_.settings.rigidify) return;
    const auto np = static_cast<int32_t>(w_.pieces.size());
    const double limit = w_.settings.rigidStrainRate;
#pragma omp parallel for schedule(dynamic, 1)
    for (int32_t p = 0; p < np; ++p) {
        if (!w_.sleeping.deformable(p)) {
            if (w_.sleeping.asleep(p)) belowFor_[p] = 0;
            continue;
        }
        const PieceInfo& P = w_.pieces[p];
        const double* x = w_.pos.data();
        const double* v = w_.vel.data();
        const uint8_t* blk = w_.blocked.data();
        if (std::any_of(blk + P.nodeBegin, blk + P.nodeEnd, [](uint8_t d) { return d != 0; })) {
            // moved through prescribed DOFs: never rigid
            rate_[p] = std::numeric_limits<double>::infinity();
            belowFor_[p] = 0;
            continue;
        }
        const RigidFit fit = fitRigidMotion(x, v, w_.mass.data(), P.nodeBegin, P.nodeEnd);
        const Vec3 &c = fit.c, &V = fit.V, &w = fit.w;
        double dev2 = 0;
        for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n) {
            const Vec3 r = Vec3(x[3 * n], x[3 * n + 1], x[3 * n + 2]) - c;
            dev2 = std::max(dev2, (Vec3(v[3 * n], v[3 * n + 1], v[3 * n + 2]) - V - w.cross(r)).squaredNorm());
        }
        rate_[p] = std::sqrt(dev2) / minEdge_[p];
        belowFor_[p] = rate_[p] < limit ? belowFor_[p] + dt : 0.0;
    }
}

bool RigidBodies::wantsRigid(std::size_t p) const {
    return w_.settings.rigidify && w_.sleeping.deformable(p) && w_.sleeping.dynamic(p) &&
           rate_[p] < w_.settings.rigidStrainRate && belowFor_[p] >= w_.settings.rigidTime;
}

bool RigidBodies::wantsDeformable(std::size_t p) const {
    return w_.sleeping.rigid(p) && (!w_.settings.rigidify || wake_[p]);
}

void RigidBodies::saveFields(WorldState& s) const {
    s.put("rigidBody", body_.data(), body_.size());
    s.put("rigidOffset", offset_.data(), offset_.size());
    s.put("rigidLoad0", load0_.data(), load0_.size());
    s.put("rigidLoadSet", loadSet_.data(), loadSet_.size());
    s.put("rigidBelowFor", belowFor_.data(), belowFor_.size());
    s.put("rigidRate", rate_.data(), rate_.size());
    s.put("rigidWake", wake_.data(), wake_.size());
}

void RigidBodies::checkFields(const WorldState& s) const {
    if (s.fields.count("rigidBody") == 0) return;  // (files from before adaptive rigidity)
    s.check<double>("rigidBody", body_.size());
    s.check<double>("rigidOffset", offset_.size());
    s.check<double>("rigidLoad0", load0_.size());
    s.check<uint8_t>("rigidLoadSet", loadSet_.size());
    s.check<double>("rigidBelowFor", belowFor_.size());
    s.check<double>("rigidRate", rate_.size());
    s.check<uint8_t>("rigidWake", wake_.size());
}

void RigidBodies::loadFields(const WorldState& s) {
    if (s.fields.count("rigidBody") == 0) {
        std::fill(body_.begin(), body_.end(), 0.0);
        std::fill(belowFor_.begin(), belowFor_.end(), 0.0);
        std::fill(wake_.begin(), wake_.end(), 0);
        return;
    }
    s.get("rigidBody", body_.data(), body_.size());
    s.get("rigidOffset", offset_.data(), offset_.size());
    s.get("rigidLoad0", load0_.data(), load0_.size());
    s.get("rigidLoadSet", loadSet_.data(), loadSet_.size());
    s.get("rigidBelowFor", belowFor_.data(), belowFor_.size());
    s.get("rigidRate", rate_.data(), rate_.size());
    s.get("rigidWake", wake_.data(), wake_.size());
}

}  // namespace qdem
