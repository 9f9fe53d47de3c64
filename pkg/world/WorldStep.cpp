// The step pipeline: obstacle contacts, element forces, leapfrog update.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "../contact/ContactLaw.hpp"
#include "../core/Errors.hpp"
#include "../core/Threads.hpp"
#include "../element/ElementKernel.hpp"
#include "../element/MaterialLaw.hpp"
#include "World.hpp"

namespace qdem {

void World::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError("QDEM: time step must be a positive finite number");
    const ThreadScope threads;  // QDEM's thread count for this step, YADE's restored after
    double t0 = omp_get_wtime();
    if (obstaclesPending_ || gravityPending_) checkLoadedRest();
    contactsActive_ = false;
    if (settings.trackEnergy) {
        energy.contactElastic = 0;  // a state: summed afresh by the contact phases
        beginPieceEnergy();
    }
    updatePieceBounds();
    obstaclePhase(dt);
    const double tObs = omp_get_wtime();
    pieceContactPhase(dt);
    sphereContactPhase(dt);
    double t1 = omp_get_wtime();
    elementPhase(dt);
    double t2 = omp_get_wtime();
    integratePhase(dt);
    if (settings.trackEnergy) finishPieceEnergy();
    double t3 = omp_get_wtime();
    timings.obstacles = tObs - t0;
    timings.elements = t2 - t1;
    timings.integrate = t3 - t2;
    time += dt;
    ++iter;
    updateSleep(dt);
}

// ---------------------------------------------------------------------------
// Element forces

template <class Law, bool Viscous, bool Energy>
void World::elementRange(const Law& law, int32_t t0, int32_t t1, const Material& m, double* buf, int32_t lo,
                         double& wEl, double& diss) const {
    const ElementParams prm{m.lambda(), m.mu(), Viscous ? m.beta() : 0.0};
    const int32_t* conn = tetNodes.data();
    double w = 0, d = 0;
    BatchOut out;
    for (int32_t e0 = t0; e0 < t1; e0 += kLanes) {
        const int count = std::min<int32_t>(kLanes, t1 - e0);
        elementBatch<Law, Viscous, Energy>(law, e0, count, conn, pos.data(), vel.data(), tetB.data(), tetVol0.data(),
                                           prm, out);
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
    if (!layout_.matches(nth, awakeVersion_)) layout_.build(tetNodes.data(), awakeTets_, nth, awakeVersion_);
    double diss = 0;
    const bool energyOn = settings.trackEnergy;
#pragma omp parallel num_threads(layout_.nThreads) reduction(+ : diss)
    {
        const int th = omp_get_thread_num();
        std::vector<double>& buf = layout_.buffers[th];
        std::fill(buf.begin(), buf.end(), 0.0);
        const int32_t lo = layout_.nodeLo[th];
        double* pe = energyOn ? threadPieceEnergy_[th].data() : nullptr;
        for (const TetSegment& sg : layout_.share[th]) {
            const Material& m = materials[pieces[sg.piece].material];
            const bool visc = settings.viscosityOn && m.viscosity > 0;
            double w = 0;
            // The law is chosen once per segment (one piece's tets): the
            // kernel below is compiled per law, with no call through a pointer.
            withLaw(m, [&](const auto& law) {
                using Law = std::decay_t<decltype(law)>;
                if (visc && energyOn) elementRange<Law, true, true>(law, sg.t0, sg.t1, m, buf.data(), lo, w, diss);
                else if (visc) elementRange<Law, true, false>(law, sg.t0, sg.t1, m, buf.data(), lo, w, diss);
                else if (energyOn) elementRange<Law, false, true>(law, sg.t0, sg.t1, m, buf.data(), lo, w, diss);
                else elementRange<Law, false, false>(law, sg.t0, sg.t1, m, buf.data(), lo, w, diss);
            });
            if (energyOn) pe[3 * sg.piece] += w;  // strain energy per piece (sleeping ones keep theirs)
        }
    }
    if (energyOn) energy.viscous += diss * dt;
}

// ---------------------------------------------------------------------------
// Node-obstacle contacts (YADE walls, boxes, facets)

void World::obstaclePhase(double dt) {
    const int nObs = static_cast<int>(obstacles.size());
    for (auto& o : obstacles) {
        o.reactionForce.setZero();
        o.reactionTorque.setZero();
    }
    // Sleeping pieces still push on obstacles with what they pushed when
    // they fell asleep.
    for (std::size_t p = 0; p < frozenReaction_.size(); ++p) {
        const std::vector<double>& fr = frozenReaction_[p];
        for (std::size_t k = 0; k + 7 <= fr.size(); k += 7) {
            Obstacle& o = obstacles[static_cast<int>(fr[k])];
            o.reactionForce += Eigen::Vector3d(fr[k + 1], fr[k + 2], fr[k + 3]);
            o.reactionTorque += Eigen::Vector3d(fr[k + 4], fr[k + 5], fr[k + 6]);
        }
    }
    pieceObstacles_.clear();
    pieceObstacleBegin_.clear();
    pairReaction_.clear();
    contactCounts.wall = 0;
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
    checkStartOverlaps();
    if (pieceObstacles_.empty()) return;

    beginContactForces();
    const int nth = omp_get_max_threads();
    // Reactions per thread and (piece, obstacle) pair: a piece that falls
    // asleep keeps its own.
    const std::size_t nPairs = pieceObstacles_.size();
    obstacleReaction_.assign(static_cast<std::size_t>(nth) * nPairs * 6, 0.0);
    const bool energyOn = settings.trackEnergy;
    const bool regularized = settings.frictionModel == FrictionModel::Regularized;
    double eDamp = 0, eSlip = 0, eBound = 0;
    // Sleeping pieces' nodes are skipped (their history kept as it is).
    const bool all = nAsleep_ == 0;
    const auto nSurf = all ? static_cast<int32_t>(surfNodes.size()) : static_cast<int32_t>(awakeSurf_.size());
    const int32_t* awakeSurf = awakeSurf_.data();

    long nWall = 0;
#pragma omp parallel num_threads(nth) reduction(+ : eDamp, eSlip, eBound, nWall)
    {
        const int th = omp_get_thread_num();
        double* react = obstacleReaction_.data() + static_cast<std::size_t>(th) * nPairs * 6;
        double* pe = energyOn ? threadPieceEnergy_[th].data() : nullptr;
#pragma omp for schedule(static)
        for (int32_t i = 0; i < nSurf; ++i) {
            const int32_t s = all ? i : awakeSurf[i];
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
                // Scaled by the node's share of the surface area (surfWeight,
                // World.hpp); the dashpots keep their damping ratio.
                const double kn = surfWeight[s] * (o.young > 0 ? 2 * m.young * o.young * m.radius / (m.young + o.young)
                                                               : 2 * m.young * m.radius);
                const double xi = dampingRatioFromRestitution(m.restitution);
                const double mu = o.friction >= 0 ? o.friction : m.frictionWall;
                const double kt = kn * 2 * (1 - m.poisson) / (2 - m.poisson);  // Mindlin's ratio
                ContactParams cp{kn, 2 * xi * std::sqrt(kn * mass[node]), kt, 2 * xi * std::sqrt(kt * mass[node]),
                                 mu, settings.frictionRegVelocity, mass[node]};
                Eigen::Vector3d sh = Eigen::Vector3d::Zero();
                if (slot >= 0) sh = Eigen::Map<Eigen::Vector3d>(shear + 3 * slot);
                const Eigen::Vector3d vo = o.velocityAt(hit.point);
                const Eigen::Vector3d vRel = v - vo;
                const ContactResult r =
                    lawForce(settings.frictionOn && mu > 0, regularized, cp, hit.normal, hit.overlap, vRel, dt, sh);
                newBody[used] = o.bodyId;
                newSide[used] = static_cast<int8_t>(hit.side);
                newShear[used] = sh;
                ++used;
                ++nWall;
                fNode += r.force;
                double* R = react + 6 * j;
                const Eigen::Vector3d torque = (hit.point - o.pos).cross(-r.force);
                for (int d = 0; d < 3; ++d) {
                    R[d] -= r.force[d];
                    R[3 + d] += torque[d];
                }
                if (energyOn) {
                    pe[3 * ip + 1] += r.elastic;
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
    contactCounts.wall = nWall;
    pairReaction_.assign(6 * nPairs, 0.0);
    for (int th = 0; th < nth; ++th)
        for (std::size_t j = 0; j < 6 * nPairs; ++j)
            pairReaction_[j] += obstacleReaction_[static_cast<std::size_t>(th) * nPairs * 6 + j];
    for (std::size_t j = 0; j < nPairs; ++j) {
        const double* R = &pairReaction_[6 * j];
        Obstacle& o = obstacles[pieceObstacles_[j]];
        o.reactionForce += Eigen::Vector3d(R[0], R[1], R[2]);
        o.reactionTorque += Eigen::Vector3d(R[3], R[4], R[5]);
    }
    if (energyOn) {
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
    const bool energyOn = settings.trackEnergy;
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
    const double damp = settings.localDamping;
    // Sleeping pieces are skipped: then only the awake nodes are visited.
    const bool all = nAsleep_ == 0;
    const int32_t* ids = awakeNodes_.data();
    const auto count = all ? N : static_cast<int32_t>(awakeNodes_.size());
    const bool sleepOn = settings.sleepVelocity > 0;
    if (sleepOn) {
        threadSpeed2_.resize(nth);
        for (auto& t : threadSpeed2_) t.assign(pieces.size(), 0.0);
    }
#pragma omp parallel num_threads(nth) reduction(+ : ek, eg, ed)
    {
        double* speed2 = sleepOn ? threadSpeed2_[omp_get_thread_num()].data() : nullptr;
#pragma omp for schedule(static)
        for (int32_t i = 0; i < count; ++i) {
            const int32_t n = all ? i : ids[i];
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
            if (speed2) {
                const double v2 = V[3 * n] * V[3 * n] + V[3 * n + 1] * V[3 * n + 1] + V[3 * n + 2] * V[3 * n + 2];
                double& m = speed2[nodePiece[n]];
                m = std::max(m, v2);
            }
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
        const ElementParams prm{m.lambda(), m.mu(), settings.viscosityOn ? m.beta() : 0.0};
        const int32_t* c = tetNodes.data() + 4 * e;
        const Mat3 B = loadRowMajor(tetB.data() + 9 * e);
        const double* X = pos.data();
        const double* V = vel.data();
        const Mat3 F = edgeMatrix(X + 3 * c[0], X + 3 * c[1], X + 3 * c[2], X + 3 * c[3]) * B;
        const Mat3 Fd = edgeMatrix(V + 3 * c[0], V + 3 * c[1], V + 3 * c[2], V + 3 * c[3]) * B;
        const Mat3 P = withLaw(m, [&](const auto& law) {
            using Law = std::decay_t<decltype(law)>;
            return tetStress<Law, true, false>(law, F, Fd, prm).P;
        });
        // sigma = P F^T / J (for J <= 0 the element is inverted: the number
        // is the law's, signs and all)
        const Mat3 sigma = (P * F.transpose()) / F.determinant();
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
