// Leapfrog integration of the nodes, the same scheme as YADE's
// NewtonIntegrator (velocities at half steps), with gravity, external and
// contact forces, Cundall's local damping and prescribed (blocked) DOFs.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../core/ThreadPartials.hpp"
#include "../parallel/Domain.hpp"
#include "../step/WorldState.hpp"
#include "ElementPhase.hpp"
#include "../step/AwakeSet.hpp"
#include "IntegrationPhase.hpp"

namespace qdem {

IntegrationPhase::NodeUpdate IntegrationPhase::nodeUpdate() {
    NodeUpdate u;
    const auto N = static_cast<int32_t>(w_.mass.size());
    const ThreadLayout& layout = w_.elements.layout();
    u.nth = layout.nThreads;
    u.withContacts = w_.contacts.active;
    for (int d = 0; d < 3; ++d) u.g[d] = w_.gravity[d];
    u.X = w_.pos.data();
    u.V = w_.vel.data();
    u.Fout = w_.force.data();
    u.Fext = w_.extForce.data();
    u.Fc = w_.contacts.force.data();
    u.M = w_.mass.data();
    // Under MPI: what other ranks computed on this rank's nodes (Domain.hpp).
    u.Fg = w_.domain.any() ? w_.domain.any()->ghostForce() : nullptr;
    u.blk = w_.blocked.data();
    u.nodePiece = w_.nodePiece.data();
    u.damp = w_.settings.localDamping;
    // Sleeping pieces are skipped: then only the awake nodes are visited.
    u.all = w_.sleeping.everything();
    u.ids = w_.sleeping.awakeNodes().data();
    u.count = u.all ? N : static_cast<int32_t>(w_.sleeping.awakeNodes().size());
    u.sleepOn = w_.settings.sleepVelocity > 0;
    if (u.sleepOn) {
        threadSpeed2_.resize(u.nth);
        for (auto& t : threadSpeed2_) t.assign(w_.pieces.size(), 0.0);
    }
    // The element phase's thread buffers as flat arrays (no vector of
    // vectors to walk per node and thread).
    bufPtr_.resize(u.nth);
    bufLo_.resize(u.nth);
    bufHi_.resize(u.nth);
    for (int t = 0; t < u.nth; ++t) {
        bufPtr_[t] = layout.buffers[t].data();
        bufLo_[t] = layout.nodeLo[t];
        bufHi_[t] = layout.nodeHi[t];
    }
    u.buf = bufPtr_.data();
    u.stride = layout.stride;
    u.bufLo = bufLo_.data();
    u.bufHi = bufHi_.data();
    return u;
}

const double* IntegrationPhase::viscousCorrection(const NodeUpdate u, bool implicit, double dt) {
    viscous_.iterations = 0;
    viscous_.startedWarm = false;
    viscous_.seconds = 0;
    if (!implicit) return nullptr;
#pragma omp parallel for num_threads(u.nth) schedule(static)
    for (int32_t i = 0; i < u.count; ++i) u.explicitForce(u.all ? i : u.ids[i], u.Fout + 3 * (u.all ? i : u.ids[i]));
    return viscous_.solve(dt, u.Fout);
}

template <bool Implicit, bool Damp, bool EnergyOn, bool SleepOn>
std::array<double, 5> IntegrationPhase::advance(const NodeUpdate u, double dt, const double* Fq, double* dV) {
    ThreadPartials<5> parts(u.nth);  // the threads' sums, added in thread order
#pragma omp parallel num_threads(u.nth)
    {
        double ekT = 0, egT = 0, edT = 0, ebT = 0, sumT = 0;
        double* speed2 = SleepOn ? threadSpeed2_[omp_get_thread_num()].data() : nullptr;
#pragma omp for schedule(static) nowait  // (the region ends with the loop: its join is the barrier)
        for (int32_t i = 0; i < u.count; ++i) {
            const int32_t n = u.all ? i : u.ids[i];
            double f[3];
            if constexpr (Implicit)
                for (int d = 0; d < 3; ++d) f[d] = u.Fout[3 * n + d] - Fq[3 * n + d];
            else
                u.explicitForce(n, f);
            const double invM = 1.0 / u.M[n];
            for (int d = 0; d < 3; ++d) {
                u.Fout[3 * n + d] = f[d];
                const double vOld = u.V[3 * n + d];
                const bool free = !((u.blk[n] >> d) & 1u);
                if constexpr (Damp)
                    if (free) {  // YADE's rule: against the mid-step velocity
                        const double vm = vOld + 0.5 * dt * f[d] * invM;
                        const double fd = u.damp * std::fabs(f[d]) * (vm > 0 ? 1.0 : (vm < 0 ? -1.0 : 0.0));
                        f[d] -= fd;
                        if constexpr (EnergyOn) edT += fd * vm * dt;
                    }
                // (f * 0 on a blocked DOF: a non-finite force there is reported, as in advancePlain)
                const double a = f[d] * (free ? invM : 0.0);
                if constexpr (EnergyOn) {
                    const double vMid = vOld + 0.5 * dt * a;  // velocity at the integer time level
                    ekT += 0.5 * u.M[n] * vMid * vMid;
                    egT -= u.M[n] * u.g[d] * vOld * dt;
                    // Booked as gravity is: -(work of the external force),
                    // and on a blocked DOF -(work of the constraint),
                    // whose force -f keeps the velocity (ledger closed for
                    // loaded and driven pieces: doc/formulation.md §2).
                    ebT -= u.Fext[3 * n + d] * vOld * dt;
                    if (!free) ebT += f[d] * vOld * dt;
                }
                u.V[3 * n + d] = vOld + dt * a;
                if (Implicit && dV) dV[3 * n + d] = dt * a;  // (the move waits for the energy term, on x_n)
                else u.X[3 * n + d] += dt * u.V[3 * n + d];
            }
            // Every step, so that no run ends on a NaN it did not report:
            // the sum of the new positions and velocities is finite iff
            // each of them is (no scene's coordinates sum near 1e308).
            // Six additions; per-value isfinite tests cost the update 20 %.
            sumT += (u.V[3 * n] + u.V[3 * n + 1] + u.V[3 * n + 2]) + (u.X[3 * n] + u.X[3 * n + 1] + u.X[3 * n + 2]);
            if constexpr (SleepOn) {
                const double v2 =
                    u.V[3 * n] * u.V[3 * n] + u.V[3 * n + 1] * u.V[3 * n + 1] + u.V[3 * n + 2] * u.V[3 * n + 2];
                double& m = speed2[u.nodePiece[n]];
                m = std::max(m, v2);
            }
        }
        parts.set(omp_get_thread_num(), {ekT, egT, edT, ebT, sumT});
    }
    const std::array<double, 5> s = parts.sum();
    return std::array<double, 5>{s[0], s[1], s[2], std::isfinite(s[4]) ? 1.0 : 0.0, s[3]};
}

std::array<double, 5> IntegrationPhase::advanceAny(const NodeUpdate u, double dt, const double* Fq, double* dV,
                                                   bool energyOn) {
    // (implicit, damping, energy, sleep) from run-time flags to compile-time ones
    const auto withFlag = [](bool on, auto&& next) {
        return on ? next(std::true_type{}) : next(std::false_type{});
    };
    return withFlag(Fq != nullptr, [&](auto im) {
        return withFlag(u.damp > 0, [&](auto dm) {
            return withFlag(energyOn, [&](auto en) {
                return withFlag(u.sleepOn, [&](auto sl) {
                    return advance<decltype(im)::value, decltype(dm)::value, decltype(en)::value,
                                   decltype(sl)::value>(u, dt, Fq, dV);
                });
            });
        });
    });
}

void IntegrationPhase::run(double dt) {
    const NodeUpdate u = nodeUpdate();
    const bool energyOn = w_.settings.trackEnergy;
    // Implicit viscosity (ViscousSolve.hpp): the explicit forces first, then
    // the viscous correction q, applied as the force f - q.
    const bool implicit = viscous_.active();
    const double* Fq = viscousCorrection(u, implicit, dt);
    double* dV = implicit && energyOn ? viscous_.velocityChange() : nullptr;
    // The common step (explicit, no damping or sleep tracking, every node
    // awake; the energy ledger on or off) has a loop of its own, vectorised
    // over DOFs.
    if (!implicit && !(u.damp > 0) && !u.sleepOn && u.all) {
        const std::array<double, 4> r = energyOn ? advancePlain<true>(dt) : advancePlain<false>(dt);
        if (r[3] == 0) reportNotFinite(u.ids, u.all, u.count, u.Fout);
        if (energyOn) {
            w_.energy.kinetic = r[0];
            w_.energy.gravity += r[1];
            w_.energy.boundaryWork += r[2];
        }
        advanceRigid(dt, energyOn, u.sleepOn);
        return;
    }
    // The update, compiled per combination of the implicit solve, local
    // damping, energy tracking and sleep tracking: the common run (explicit,
    // none of the three) carries no test of them per node and DOF.
    const std::array<double, 5> e = advanceAny(u, dt, Fq, dV, energyOn);
    if (e[3] == 0) reportNotFinite(u.ids, u.all, u.count, u.Fout);
    if (dV) {
        w_.energy.viscous += viscous_.dissipation(dt, u.V);
#pragma omp parallel for num_threads(u.nth) schedule(static)
        for (int32_t i = 0; i < u.count; ++i) {
            const int32_t n = u.all ? i : u.ids[i];
            for (int d = 0; d < 3; ++d) u.X[3 * n + d] += dt * u.V[3 * n + d];
        }
    }
    if (energyOn) {
        w_.energy.kinetic = e[0];
        w_.energy.gravity += e[1];
        w_.energy.localDamping += e[2];
        w_.energy.boundaryWork += e[4];
    }
    advanceRigid(dt, energyOn, u.sleepOn);
}

void IntegrationPhase::advanceRigid(double dt, bool energyOn, bool sleepOn) {
    rigid_.forgetStale();
    if (w_.sleeping.nRigid() > 0) {
        const RigidBodies::StepSums r = rigid_.advance(dt, sleepOn ? threadSpeed2_[0].data() : nullptr);
        if (!r.finite)
            throw StabilityError(cat("QDEM: during step ", w_.iter + 1, " (t=", w_.time, " s) a rigid piece's state ",
                                     "became not finite (settings.rigidify): keep O.dt below ",
                                     "QdemEngine.stableTimeStep()"));
        if (energyOn) {
            w_.energy.kinetic += r.kinetic;
            w_.energy.gravity += r.gravity;
            w_.energy.boundaryWork += r.boundary;
        }
    }
    rigid_.measure(dt);
}

template <bool EnergyOn>
std::array<double, 4> IntegrationPhase::advancePlain(double dt) {
    // What the generic loop above does per node and DOF, in tiles of nodes
    // taken as flat arrays of DOFs: the force summed term by term in the
    // same order (so the same bits), then one branch-free update that the
    // compiler vectorises. The generic loop spent ~10 ns per node, mostly
    // on its per-node test of every thread buffer's range and on reloads
    // of its captures after each store (issue 16).
    constexpr int32_t kTile = 256;
    const auto N = static_cast<int32_t>(w_.mass.size());
    const ThreadLayout& layout = w_.elements.layout();
    const int nth = layout.nThreads;
    const int stride = layout.stride;
    const double g0 = w_.gravity[0], g1 = w_.gravity[1], g2 = w_.gravity[2];
    double* const X = w_.pos.data();
    double* const V = w_.vel.data();
    double* const Fout = w_.force.data();
    const double* const Fext = w_.extForce.data();
    const double* const Fc = w_.contacts.active ? w_.contacts.force.data() : nullptr;
    const double* const Fg = w_.domain.any() ? w_.domain.any()->ghostForce() : nullptr;
    const double* const M = w_.mass.data();
    const uint8_t* const blk = w_.blocked.data();
    ThreadPartials<4> parts(nth);  // the threads' sums, added in thread order
#pragma omp parallel num_threads(nth)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        double sum = 0, ek = 0, eg = 0, eb = 0;
        const auto first = static_cast<int32_t>(static_cast<int64_t>(N) * t / nt);
        const auto last = static_cast<int32_t>(static_cast<int64_t>(N) * (t + 1) / nt);
        alignas(64) double inv3[3 * kTile];  // 1/m per DOF, 0 on a blocked one
        // With the energy ledger: the mass and gravity per DOF.
        alignas(64) double m3[EnergyOn ? 3 * kTile : 1];
        alignas(64) double g3[EnergyOn ? 3 * kTile : 1];
        if constexpr (EnergyOn)
            for (int32_t j = 0; j < kTile; ++j) g3[3 * j] = g0, g3[3 * j + 1] = g1, g3[3 * j + 2] = g2;
        for (int32_t s = first; s < last; s += kTile) {
            const int32_t e = std::min(last, s + kTile);
            const int32_t len = e - s;
            double* __restrict f = Fout + 3 * static_cast<std::ptrdiff_t>(s);
            const double* __restrict fx = Fext + 3 * static_cast<std::ptrdiff_t>(s);
            const double* __restrict m = M + s;
            for (int32_t j = 0; j < len; ++j) {
                f[3 * j] = fx[3 * j] + m[j] * g0;
                f[3 * j + 1] = fx[3 * j + 1] + m[j] * g1;
                f[3 * j + 2] = fx[3 * j + 2] + m[j] * g2;
            }
            for (int b = 0; b < nth; ++b) {
                const int32_t lo = std::max(s, layout.nodeLo[b]), hi = std::min(e - 1, layout.nodeHi[b]);
                if (lo > hi) continue;
                const double* __restrict src = layout.buffers[b].data() + stride * (lo - layout.nodeLo[b]);
                double* __restrict dst = f + 3 * (lo - s);
                for (int32_t j = 0; j <= hi - lo; ++j) {
                    dst[3 * j] += src[stride * j];
                    dst[3 * j + 1] += src[stride * j + 1];
                    dst[3 * j + 2] += src[stride * j + 2];
                }
            }
            if (Fc) {
                const double* __restrict c = Fc + 3 * static_cast<std::ptrdiff_t>(s);
                for (int32_t k = 0; k < 3 * len; ++k) f[k] += c[k];
            }
            if (Fg) {
                const double* __restrict c = Fg + 3 * static_cast<std::ptrdiff_t>(s);
                for (int32_t k = 0; k < 3 * len; ++k) f[k] += c[k];
            }
            for (int32_t j = 0; j < len; ++j) {
                const double im = 1.0 / m[j];
                const unsigned bl = blk[s + j];
                inv3[3 * j] = (bl & 1u) ? 0.0 : im;
                inv3[3 * j + 1] = (bl & 2u) ? 0.0 : im;
                inv3[3 * j + 2] = (bl & 4u) ? 0.0 : im;
                if constexpr (EnergyOn) m3[3 * j] = m3[3 * j + 1] = m3[3 * j + 2] = m[j];
            }
            // A blocked DOF keeps its velocity: its acceleration f * 0 is 0
            // (and NaN for a non-finite force, which is then reported).
            double* __restrict v = V + 3 * static_cast<std::ptrdiff_t>(s);
            double* __restrict x = X + 3 * static_cast<std::ptrdiff_t>(s);
            if constexpr (EnergyOn) {
                // The generic loop's ledger terms, per DOF.
#pragma omp simd reduction(+ : sum, ek, eg, eb)
                for (int32_t k = 0; k < 3 * len; ++k) {
                    const double vOld = v[k];
                    const double a = f[k] * inv3[k];
                    const double vMid = vOld + 0.5 * dt * a;
                    ek += 0.5 * m3[k] * vMid * vMid;
                    eg -= m3[k] * g3[k] * vOld * dt;
                    eb -= fx[k] * vOld * dt;
                    eb += inv3[k] == 0.0 ? f[k] * vOld * dt : 0.0;  // a blocked DOF: -(work of the constraint)
                    const double vNew = vOld + dt * a;
                    const double xNew = x[k] + dt * vNew;
                    v[k] = vNew;
                    x[k] = xNew;
                    sum += vNew + xNew;
                }
            } else {
#pragma omp simd reduction(+ : sum)
                for (int32_t k = 0; k < 3 * len; ++k) {
                    const double vNew = v[k] + dt * (f[k] * inv3[k]);
                    const double xNew = x[k] + dt * vNew;
                    v[k] = vNew;
                    x[k] = xNew;
                    sum += vNew + xNew;  // finite iff every value is (see the generic loop)
                }
            }
        }
        parts.set(t, {ek, eg, eb, sum});
    }
    const std::array<double, 4> tot = parts.sum();
    return {tot[0], tot[1], tot[2], std::isfinite(tot[3]) ? 1.0 : 0.0};
}

void IntegrationPhase::reportNotFinite(const int32_t* ids, bool all, int32_t count, const double* force) const {
    const auto finite3 = [](const double* a) {
        return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]);
    };
    for (int32_t i = 0; i < count; ++i) {
        const int32_t n = all ? i : ids[i];
        if (finite3(&w_.vel[3 * n]) && finite3(&w_.pos[3 * n])) continue;
        const int32_t piece = w_.nodePiece[n];
        const int32_t local = n - w_.pieces[piece].nodeBegin;
        const std::string where = cat("QDEM: during step ", w_.iter + 1, " (t=", w_.time, " s) node ", local,
                                      " of piece ", piece, " has a ", finite3(&w_.vel[3 * n]) ? "position" : "velocity",
                                      " that is not finite");
        if (!finite3(&w_.extForce[3 * n]))
            throw StabilityError(cat(where, ": its external force is not finite (piece.extForce[", local, "] = (",
                                     w_.extForce[3 * n], ", ", w_.extForce[3 * n + 1], ", ", w_.extForce[3 * n + 2],
                                     ")). Set finite external forces."));
        if (!std::isfinite(w_.mass[n]) || !(w_.mass[n] > 0))
            throw StabilityError(cat(where, ": its mass is ", w_.mass[n], "."));
        throw StabilityError(cat(where, " (force on it (", force[3 * n], ", ", force[3 * n + 1], ", ", force[3 * n + 2],
                                 ")). Either a NaN was written into the piece's pos or vel arrays, or the ",
                                 "integration blew up: keep O.dt below QdemEngine.stableTimeStep() (QdemEngine's ",
                                 "checkDt names a stiffened element before this happens)."));
    }
    throw StabilityError(cat("QDEM: during step ", w_.iter + 1, " a node state became not finite"));  // (not reached)
}

void IntegrationPhase::report(PhaseReport& r) const {
    r.seconds.push_back({name(), seconds - viscous_.seconds});
    r.seconds.push_back({"viscousSolve", viscous_.seconds});
    r.counts.push_back({"viscousIterations", viscous_.iterations});
    r.counts.push_back({"viscousWarmStart", viscous_.startedWarm ? 1 : 0});  // the last solve started warm
    r.counts.push_back({"viscousIterationsTotal", viscous_.totalIterations});  // since the world was built
    r.counts.push_back({"viscousFactorizations", viscous_.factorizations()});  // Cholesky preconditioner, since built
}

void IntegrationPhase::stateColumns(StateColumns& c) {
    c.add("viscousWarmStart", viscous_.warmStart(), Rows::Node, /*restart=*/false);  // (saveFields: optional)
}

void IntegrationPhase::piecesAdded() {
    // The new nodes have no last velocity change; the others keep theirs.
    viscous_.warmStart().resize(3 * w_.mass.size(), 0.0);
    rigid_.piecesAdded();
}

void IntegrationPhase::saveFields(WorldState& s) const {
    const std::vector<double>& w = viscous_.warmStart();
    s.put("viscousWarmStart", w.data(), w.size());
    const double meta[2] = {static_cast<double>(viscous_.warmIter), viscous_.warmDt};
    s.put("viscousWarmStep", meta, 2);
    rigid_.saveFields(s);
}

void IntegrationPhase::checkFields(const WorldState& s) const {
    rigid_.checkFields(s);
    if (s.fields.count("viscousWarmStart") == 0) return;
    s.check<double>("viscousWarmStart", viscous_.warmStart().size());
    s.check<double>("viscousWarmStep", 2);
}

void IntegrationPhase::loadFields(const WorldState& s) {
    rigid_.loadFields(s);
    std::vector<double>& w = viscous_.warmStart();
    if (s.fields.count("viscousWarmStart") == 0) {
        std::fill(w.begin(), w.end(), 0.0);
        viscous_.warmIter = -1;
        return;
    }
    s.get("viscousWarmStart", w.data(), w.size());
    double meta[2];
    s.get("viscousWarmStep", meta, 2);
    viscous_.warmIter = static_cast<long>(meta[0]);
    viscous_.warmDt = meta[1];
}

double IntegrationPhase::maxSpeed2(std::size_t piece) const {
    double m = 0;
    for (const auto& t : threadSpeed2_) m = std::max(m, t[piece]);
    return m;
}

}  // namespace qdem
