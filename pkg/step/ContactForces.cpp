#include "ContactForces.hpp"

namespace qdem {

void ContactForces::begin() {
    if (active) return;
    for (std::size_t p = 0; p < pieces_.size(); ++p) {
        if (sleeping_.asleep(p) && sleeping_.dynamic(p)) continue;  // (held ones touch obstacles: ObstaclePhase)
        for (int32_t i = pieces_[p].surfBegin; i < pieces_[p].surfEnd; ++i)
            for (int d = 0; d < 3; ++d) force[3 * surfNodes_[i] + d] = 0.0;
    }
    active = true;
}

}  // namespace qdem
