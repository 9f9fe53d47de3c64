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
    obstaclePhase_.run(dt);
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
