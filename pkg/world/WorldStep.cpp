// The step pipeline: obstacle contacts, element forces, leapfrog update.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../core/Errors.hpp"
#include "../core/Threads.hpp"
#include "../element/SvkBatch.hpp"
#include "World.hpp"

namespace qdem {

void World::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError("QDEM: time step must be a positive finite number");
    const ThreadScope threads;  // QDEM's thread count for this step, YADE's restored after
    double t0 = omp_get_wtime();
    contactsActive_ = false;
    if (trackEnergy) energy.contactElastic = 0;  // a state: summed afresh by the contact phases
    updatePieceBounds();
    obstaclePhase(dt);
    const double tObs = omp_get_wtime();
    pieceContactPhase(dt);
    sphereContactPhase(dt);
    double t1 = omp_get_wtime();
    elementPhase(dt);
    double t2 = omp_get_wtime();
    integratePhase(dt);
    double t3 = omp_get_wtime();
    timings.obstacles = tObs - t0;
    timings.elements = t2 - t1;
    timings.integrate = t3 - t2;
    time += dt;
    ++iter;
}

// ---------------------------------------------------------------------------
// Element forces

template <bool Viscous, bool Energy>
void World::elementRange(int32_t t0, int32_t t1, const Material& m, double* buf, int32_t lo, double& wEl,
                         double& diss) const {
    const ElementParams prm{m.lambda(), m.mu(), Viscous ? m.beta() : 0.0};
    const int32_t* conn = tetNodes.data();
    double w = 0, d = 0;
    BatchOut out;
    for (int32_t e0 = t0; e0 < t1; e0 += kLanes) {
        const int count = std::min<int32_t>(kLanes, t1 - e0);
        svkBatch<Viscous, Energy>(e0, count, conn, pos.data(), vel.data(), tetB.data(), tetVol0.data(), prm, out);
        for (int l = 0; l < count; ++l) {
            const int32_t* c = conn + 4 * (e0 + l);
            for (int k = 0; k < 4; ++k) {
                double* o = buf + 3 * (c[k] - lo);
                o[0] += out.f[k][0][l];
                o[1] += out.f[k][1][l];
                o[2] += out.f[k][2][l];
            }
            if constexpr (Energy) {
                w += out.wElastic[l];
                d += out.diss[l];
            }
        }
    }
    wEl += w;
    diss += d;
}

void World::elementPhase(double dt) {
    const int nth = omp_get_max_threads();
    if (!layout_.matches(nth, nTets())) layout_.build(tetNodes.data(), nTets(), nth);
    double wEl = 0, diss = 0;
    const bool energyOn = trackEnergy;
#pragma omp parallel num_threads(layout_.nThreads) reduction(+ : wEl, diss)
    {
        const int th = omp_get_thread_num();
        std::vector<double>& buf = layout_.buffers[th];
        std::fill(buf.begin(), buf.end(), 0.0);
        const int32_t lo = layout_.nodeLo[th];
        const int32_t c0 = layout_.tetBegin[th], c1 = layout_.tetBegin[th + 1];
        for (const PieceInfo& p : pieces) {
            const int32_t a = std::max(c0, p.tetBegin), b = std::min(c1, p.tetEnd);
            if (a >= b) continue;
            const Material& m = materials[p.material];
            const bool visc = viscosityOn && m.viscosity > 0;
            if (visc && energyOn) elementRange<true, true>(a, b, m, buf.data(), lo, wEl, diss);
            else if (visc) elementRange<true, false>(a, b, m, buf.data(), lo, wEl, diss);
            else if (energyOn) elementRange<false, true>(a, b, m, buf.data(), lo, wEl, diss);
            else elementRange<false, false>(a, b, m, buf.data(), lo, wEl, diss);
        }
    }
    if (energyOn) {
        energy.elastic = wEl;
        energy.viscous += diss * dt;
    }
}

// ---------------------------------------------------------------------------
// Node-obstacle contacts (YADE walls, boxes, facets)

void World::obstaclePhase(double dt) {
    const int nObs = static_cast<int>(obstacles.size());
    for (auto& o : obstacles) {
        o.reactionForce.setZero();
        o.reactionTorque.setZero();
    }
    if (nObs == 0 || surfNodes.size() == 0) return;

    // Which obstacles can each piece reach this step (bounding boxes + radius)?
    pieceObstacleBegin_.assign(pieces.size() + 1, 0);
    pieceObstacles_.clear();
    for (std::size_t ip = 0; ip < pieces.size(); ++ip) {
        const Eigen::Map<const Eigen::Vector3d> lo(&pc_.pieceLo[3 * ip]), hi(&pc_.pieceHi[3 * ip]);
        const double r = materials[pieces[ip].material].radius;
        for (int i = 0; i < nObs; ++i) {
            const Obstacle& o = obstacles[i];
            bool near;
            if (o.kind == ObstacleKind::Wall) {
                // The piece's box is already grown by r; a centre within r of
                // the plane (on an allowed side) can touch it.
                const double w = o.pos[o.axis];
                if (o.sense > 0) near = lo[o.axis] <= w + r && hi[o.axis] >= w - r;
                else if (o.sense < 0) near = hi[o.axis] >= w - r && lo[o.axis] <= w + r;
                else near = lo[o.axis] <= w + r && hi[o.axis] >= w - r;
            } else {
                near = (lo.array() <= o.hi.array()).all() && (hi.array() >= o.lo.array()).all();
            }
            if (near) pieceObstacles_.push_back(i);
        }
        pieceObstacleBegin_[ip + 1] = static_cast<int>(pieceObstacles_.size());
    }
    if (pieceObstacles_.empty()) return;

    beginContactForces();
    const int nth = omp_get_max_threads();
    obstacleReaction_.assign(static_cast<std::size_t>(nth) * nObs * 6, 0.0);
    const bool energyOn = trackEnergy;
    const bool regularized = frictionModel == FrictionModel::Regularized;
    double eEl = 0, eDamp = 0, eSlip = 0, eBound = 0;
    const auto nSurf = static_cast<int32_t>(surfNodes.size());

#pragma omp parallel num_threads(nth) reduction(+ : eEl, eDamp, eSlip, eBound)
    {
        double* react = obstacleReaction_.data() + static_cast<std::size_t>(omp_get_thread_num()) * nObs * 6;
#pragma omp for schedule(static)
        for (int32_t s = 0; s < nSurf; ++s) {
            const int32_t node = surfNodes[s];
            const int ip = nodePiece[node];
            const int ob0 = pieceObstacleBegin_[ip], ob1 = pieceObstacleBegin_[ip + 1];
            int32_t* body = &slotBody_[kSlots * s];
            double* shear = &slotShear_[3 * kSlots * s];
            int8_t* side = &slotSide_[kSlots * s];
            if (ob0 == ob1) {  // nothing near this piece: forget the history
                for (int k = 0; k < kSlots; ++k) body[k] = -1;
                continue;
            }
            const Material& m = materials[pieces[ip].material];
            const Eigen::Map<const Eigen::Vector3d> x(&pos[3 * node]);
            const Eigen::Map<const Eigen::Vector3d> v(&vel[3 * node]);
            int32_t newBody[kSlots];
            int8_t newSide[kSlots];
            Eigen::Vector3d newShear[kSlots];
            int used = 0;
            Eigen::Vector3d fNode = Eigen::Vector3d::Zero();
            for (int j = ob0; j < ob1; ++j) {
                const int io = pieceObstacles_[j];
                const Obstacle& o = obstacles[io];
                int slot = -1;
                for (int k = 0; k < kSlots; ++k)
                    if (body[k] == o.bodyId) slot = k;
                ObstacleHit hit;
                if (!touchObstacle(o, x, m.radius, slot >= 0 ? side[slot] : 0, hit)) continue;
                if (used == kSlots) break;  // a node never touches more than 4 bodies at once in practice
                const double kn = o.young > 0 ? 2 * m.young * o.young * m.radius / (m.young + o.young)
                                              : 2 * m.young * m.radius;
                const double xi = dampingRatioFromRestitution(m.restitution);
                const double mu = o.friction >= 0 ? o.friction : m.frictionWall;
                const double kt = kn * 2 * (1 - m.poisson) / (2 - m.poisson);  // Mindlin's ratio
                ContactParams cp{kn, 2 * xi * std::sqrt(kn * mass[node]), kt, 2 * xi * std::sqrt(kt * mass[node]),
                                 mu, frictionRegVelocity};
                Eigen::Vector3d sh = Eigen::Vector3d::Zero();
                if (slot >= 0) sh = Eigen::Map<Eigen::Vector3d>(shear + 3 * slot);
                const Eigen::Vector3d vo = o.velocityAt(hit.point);
                const Eigen::Vector3d vRel = v - vo;
                const ContactResult r =
                    lawForce(frictionOn && mu > 0, regularized, cp, hit.normal, hit.overlap, vRel, dt, sh);
                newBody[used] = o.bodyId;
                newSide[used] = static_cast<int8_t>(hit.side);
                newShear[used] = sh;
                ++used;
                fNode += r.force;
                double* R = react + 6 * io;
                const Eigen::Vector3d torque = (hit.point - o.pos).cross(-r.force);
                for (int d = 0; d < 3; ++d) {
                    R[d] -= r.force[d];
                    R[3 + d] += torque[d];
                }
                if (energyOn) {
                    eEl += r.elastic;
                    eDamp += r.dampPower * dt;
                    eSlip += r.slipWork;
                    eBound -= r.force.dot(vo) * dt;
                }
            }
            for (int k = 0; k < kSlots; ++k) {
                body[k] = k < used ? newBody[k] : -1;
                side[k] = k < used ? newSide[k] : 0;
                if (k < used)
                    for (int d = 0; d < 3; ++d) shear[3 * k + d] = newShear[k][d];
            }
            for (int d = 0; d < 3; ++d) contactForce_[3 * node + d] += fNode[d];
        }
    }
    for (int th = 0; th < nth; ++th)
        for (int i = 0; i < nObs; ++i) {
            const double* R = obstacleReaction_.data() + (static_cast<std::size_t>(th) * nObs + i) * 6;
            obstacles[i].reactionForce += Eigen::Vector3d(R[0], R[1], R[2]);
            obstacles[i].reactionTorque += Eigen::Vector3d(R[3], R[4], R[5]);
        }
    if (energyOn) {
        energy.contactElastic += eEl;
        energy.contactDamping += eDamp;
        energy.friction += eSlip;
        energy.boundaryWork += eBound;
    }
}

// ---------------------------------------------------------------------------
// Leapfrog (same scheme as YADE's NewtonIntegrator: v at half steps)

void World::integratePhase(double dt) {
    const auto N = static_cast<int32_t>(nNodes());
    const int nth = layout_.nThreads;
    const bool energyOn = trackEnergy;
    const bool withContacts = contactsActive_;
    const double g[3] = {gravity[0], gravity[1], gravity[2]};
    double* X = pos.data();
    double* V = vel.data();
    double* Fout = force.data();
    const double* Fext = extForce.data();
    const double* Fc = contactForce_.data();
    const double* M = mass.data();
    const uint8_t* blk = blocked.data();
    double ek = 0, eg = 0, ed = 0;
    const double damp = localDamping;
#pragma omp parallel for schedule(static) num_threads(nth) reduction(+ : ek, eg, ed)
    for (int32_t n = 0; n < N; ++n) {
        double f[3] = {Fext[3 * n] + M[n] * g[0], Fext[3 * n + 1] + M[n] * g[1], Fext[3 * n + 2] + M[n] * g[2]};
        for (int t = 0; t < nth; ++t)
            if (n >= layout_.nodeLo[t] && n <= layout_.nodeHi[t]) {
                const double* b = layout_.buffers[t].data() + 3 * (n - layout_.nodeLo[t]);
                f[0] += b[0];
                f[1] += b[1];
                f[2] += b[2];
            }
        if (withContacts)
            for (int d = 0; d < 3; ++d) f[d] += Fc[3 * n + d];
        const double invM = 1.0 / M[n];
        for (int d = 0; d < 3; ++d) {
            Fout[3 * n + d] = f[d];
            const double vOld = V[3 * n + d];
            const bool free = !((blk[n] >> d) & 1u);
            if (damp > 0 && free) {  // YADE's rule: against the mid-step velocity
                const double vm = vOld + 0.5 * dt * f[d] * invM;
                const double fd = damp * std::fabs(f[d]) * (vm > 0 ? 1.0 : (vm < 0 ? -1.0 : 0.0));
                f[d] -= fd;
                if (energyOn) ed += fd * vm * dt;
            }
            const double a = free ? f[d] * invM : 0.0;
            if (energyOn) {
                const double vMid = vOld + 0.5 * dt * a;  // velocity at the integer time level
                ek += 0.5 * M[n] * vMid * vMid;
                eg -= M[n] * g[d] * vOld * dt;
            }
            V[3 * n + d] = vOld + dt * a;
            X[3 * n + d] += dt * V[3 * n + d];
        }
    }
    if (energyOn) {
        energy.kinetic = ek;
        energy.gravity += eg;
        energy.localDamping += ed;
    }
}

// ---------------------------------------------------------------------------
// Stress output

void World::computeStress(double* out) const {
    const auto T = static_cast<int32_t>(nTets());
#pragma omp parallel for schedule(static)
    for (int32_t e = 0; e < T; ++e) {
        const PieceInfo& p = pieces[tetPiece[e]];
        const Material& m = materials[p.material];
        const ElementParams prm{m.lambda(), m.mu(), viscosityOn ? m.beta() : 0.0};
        const int32_t* c = tetNodes.data() + 4 * e;
        const Mat3 B = loadRowMajor(tetB.data() + 9 * e);
        const double* X = pos.data();
        const double* V = vel.data();
        const Mat3 F = edgeMatrix(X + 3 * c[0], X + 3 * c[1], X + 3 * c[2], X + 3 * c[3]) * B;
        const Mat3 Fd = edgeMatrix(V + 3 * c[0], V + 3 * c[1], V + 3 * c[2], V + 3 * c[3]) * B;
        const TetStress st = svkStress<true, false>(F, Fd, prm);
        const Mat3 sigma = (F * st.S * F.transpose()) / F.determinant();
        double* o = out + 6 * e;
        o[0] = sigma(0, 0);
        o[1] = sigma(1, 1);
        o[2] = sigma(2, 2);
        o[3] = sigma(1, 2);
        o[4] = sigma(0, 2);
        o[5] = sigma(0, 1);
    }
}

}  // namespace qdem
