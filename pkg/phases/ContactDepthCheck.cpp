// Impacts deeper than the contact's reach stop the run the step they happen
// (doc/hard_cases.md, "Impacts deeper than the reach").
//
// A contact sees a node within its reach r_a + r_b of the other piece's
// surface; a node pushed behind that surface keeps its contact (overlap
// r_a + r_b + depth) while it stays near the face it went in through.  A
// node deeper than the reach is outside what the law models (two particles
// of radius r overlapping by more than their diameters), and as it goes on
// it meets the other piece's side faces and is pushed sideways, or loses its
// contact, whose spring energy then leaves the ledger: two 0.2 m cubes of
// E = 1e6 Pa, r = 5 mm meeting at 10 m/s each (nodes 9 reaches deep) lost
// 27 % of their energy and left with 1.9 m/s of sideways speed from a
// head-on hit.  The deep-overlap scan every checkPeriod steps
// (PieceStartOverlap.cpp) saw none of it: the whole impact fits between two
// checks.  The contact kinds keep the deepest contact of each thread as they
// go (PieceContactPhase::noteDepth: two compares per contact); this
// function, after them, reduces the threads' records and stops the run.
// Under MPI each rank judges its own contacts and World::step makes every
// rank throw the same error (Domain::finishStep).
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "../core/Errors.hpp"
#include "../parallel/Domain.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

bool PieceContactPhase::judged(int32_t pa, int32_t pb) const {
    if (startPending_ && !(startChecked_[pa] && startChecked_[pb])) return false;  // the start check's
    const std::pair<int32_t, int32_t> ab{std::min(pa, pb), std::max(pa, pb)};
    return !std::binary_search(startOverlap_.begin(), startOverlap_.end(), ab);
}

void PieceContactPhase::checkContactDepth(double dt) const {
    DeepContact d;
    for (const DeepContact& t : threadDeep_)
        if (t.node >= 0 && (d.node < 0 || t.depth / t.reach > d.depth / d.reach ||
                            (t.depth / t.reach == d.depth / d.reach && t.node < d.node)))
            d = t;
    if (d.node < 0) return;  // only pairs the start check answers for
    const PieceInfo& pa = w_.pieces[d.pa];
    const double ra = w_.materials[pa.material].radius, rb = w_.materials[w_.pieces[d.pb].material].radius;
    const double closing = std::max(0.0, -d.vn);
    // The pieces' relative speed (of their centres of mass), read
    // where every node is current (not under MPI: another rank's nodes are stale).
    double approach = NAN;
    if (!w_.domain.built()) {
        double v[2][3] = {{0, 0, 0}, {0, 0, 0}}, mass[2] = {0, 0};
        const int32_t ids[2] = {d.pa, d.pb};
        for (int k = 0; k < 2; ++k)
            for (int32_t n = w_.pieces[ids[k]].nodeBegin; n < w_.pieces[ids[k]].nodeEnd; ++n) {
                mass[k] += w_.mass[n];
                for (int c = 0; c < 3; ++c) v[k][c] += w_.mass[n] * w_.vel[3 * n + c];
            }
        double rel = 0;
        for (int c = 0; c < 3; ++c) rel += std::pow(v[0][c] / mass[0] - v[1][c] / mass[1], 2);
        approach = std::sqrt(rel);
    }
    std::ostringstream m;
    m.precision(3);
    m << "QDEM: at step " << w_.iter << " piece " << d.pa << " has sunk into piece " << d.pb
      << " deeper than their contact can see: ";
    if (d.edge)
        m << "an edge of piece " << d.pa << " has crossed one of piece " << d.pb << " by " << d.depth << " m";
    else
        m << "node " << d.node - pa.nodeBegin << " of piece " << d.pa << " (surface node, global " << d.node
          << ") is " << d.depth << " m inside piece " << d.pb;
    m << ", beyond the contact reach r_a + r_b = " << ra << " + " << rb << " = " << d.reach << " m, closing at "
      << closing << " m/s";
    if (std::isfinite(approach)) m << " (the pieces' relative speed " << approach << " m/s)";
    m << ". Deeper than the reach the contact law models nothing (particles of radius r overlapping by more than "
         "their diameters): the node meets the other piece's side faces or loses its contact, so the rebound and "
         "the energy come out silently wrong, and if it stays there the pieces interpenetrate for good. The "
         "contact is too soft for this impact or load (kn = E r per node). Use a stiffer material (QdemMat "
         "young), a larger radius r so that the reach covers the overlap (kn and the reach both grow with r: "
         "at a given speed the depth over the reach falls as r^-1.5), ";
    if (closing * dt > 0.5 * d.reach)
        m << "a smaller O.dt (the node closes " << closing * dt << " m a step against the reach " << d.reach
          << " m), ";
    m << "a smaller impact speed, or a finer mesh (more nodes share the load) (doc/hard_cases.md, \"Impacts "
         "deeper than the reach\")";
    throw StabilityError(m.str());
}

}  // namespace qdem
