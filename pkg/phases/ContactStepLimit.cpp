// The run-time stable step of the contacts as they are, serially: each awake
// surface node's contact load (ContactForces::load: the springs and dashpots
// of its piece-piece, obstacle and sphere contacts this step, ContactLoad.hpp)
// with its piece's elements, by the leapfrog condition
// 1 - dt/2 (beta w_e^2 + C/m) - dt^2/4 (w_e^2 + K/m) > 0 on that node
// (doc/formulation.md, "Piece-piece contacts as they are").  Under MPI the
// owners take it once the shares are summed (ownedStepLimit).
#include <omp.h>

#include <cmath>

#include "../material/Material.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

void PieceContactPhase::contactStepLimit(double dt) {
    stepLimit_ = ContactStepLimit{};
    if (!w_.contacts.loadActive || w_.domain.built()) return;
    const std::size_t np = w_.pieces.size();
    if (w_.pieceElementW2.size() != np || w_.pieceElementRate.size() != np) return;  // not measured
    const bool all = w_.sleeping.everything();
    const std::vector<int32_t>& awake = w_.sleeping.awakeSurf();
    const auto ns = all ? static_cast<int32_t>(w_.surfNodes.size()) : static_cast<int32_t>(awake.size());
    const double* L = w_.contacts.load.data();
    const double* M = w_.mass.data();
    const int32_t* surfNodes = w_.surfNodes.data();
    const int32_t* nodePiece = w_.nodePiece.data();
    const int32_t* awakeIds = awake.data();
    const double* w2e = w_.pieceElementW2.data();
    const double* rateE = w_.pieceElementRate.data();
    ContactStepLimit best;
#pragma omp parallel
    {
        ContactStepLimit mine;
#pragma omp for schedule(static) nowait
        for (int32_t j = 0; j < ns; ++j) {
            const int32_t s = all ? j : awakeIds[j];
            const double k = L[2 * s];
            if (!(k > 0)) continue;
            const int32_t node = surfNodes[s], p = nodePiece[node];
            const double c = L[2 * s + 1];
            const double w = std::sqrt(w2e[p] + k / M[node]);
            const double limit = leapfrogLimit(w, (rateE[p] + c / M[node]) / (2 * w));
            if (limit < mine.limit || (limit == mine.limit && node < mine.node))
                mine = ContactStepLimit{limit, node, p, k, c, w_.iter};
        }
#pragma omp critical(qdemContactStepLimit)
        if (mine.limit < best.limit || (mine.limit == best.limit && mine.node < best.node)) best = mine;
    }
    stepLimit_ = best;
    if (stepLimit_.limit < dt) checkStepLimit(dt);
}

}  // namespace qdem
