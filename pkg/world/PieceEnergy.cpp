// The energy states of the pieces (strain, contact with obstacles, contact
// with pieces: 3 per piece), summed per thread during the step; a sleeping
// piece keeps the values it had.
#include <omp.h>

#include <algorithm>

#include "Phases.hpp"
#include "World.hpp"

namespace qdem {

// Energy states per piece: a sleeping piece keeps the values it had, since
// nothing of it moves (its contacts are with sleeping pieces only while they
// are skipped).
void World::beginPieceEnergy() {
    const std::size_t nth = std::max(1, omp_get_max_threads());
    if (threadPieceEnergy_.size() < nth) threadPieceEnergy_.resize(nth);
    for (auto& t : threadPieceEnergy_) t.assign(3 * pieces.size(), 0.0);
}

void World::finishPieceEnergy() {
    double el = 0, contact = 0;
    for (std::size_t p = 0; p < pieces.size(); ++p) {
        for (int c = 0; c < 3; ++c) {
            // (obstacle contacts: also a held piece's, ObstaclePhase.cpp)
            const bool computed = c == 0   ? awake_.deformable(p)  // (a rigid piece keeps its strain)
                                  : c == 1 ? !awake_.asleep(p) || !awake_.dynamic(p)
                                           : !phases_->pieceContact.frozen(p);
            if (!computed) continue;
            double sum = 0;
            for (const auto& t : threadPieceEnergy_) sum += t[3 * p + c];
            pieceEnergy_[3 * p + c] = sum;
        }
        el += pieceEnergy_[3 * p];
        contact += pieceEnergy_[3 * p + 1] + pieceEnergy_[3 * p + 2];
    }
    energy.elastic = el;
    energy.contactElastic += contact;
}

}  // namespace qdem
