#include "PieceBounds.hpp"

#include <Eigen/Core>
#include <algorithm>

#include "../parallel/Domain.hpp"

namespace qdem {

void PieceBounds::update(bool all) {
    const std::size_t np = w_.pieces.size();
    lo.resize(3 * np);
    hi.resize(3 * np);
    if (Domain* dom = w_.domain.built()) {
        // Under MPI only this rank's surface nodes and its ghosts are current:
        // its boxes hold them (what this rank's contacts of the piece can
        // reach), empty boxes (lo > hi, touching nothing) for the others.
        for (std::size_t ip = 0; ip < np; ++ip)
            for (int d = 0; d < 3; ++d) lo[3 * ip + d] = 1e300, hi[3 * ip + d] = -1e300;
        for (const int32_t s : dom->currentSurf()) {
            const int32_t n = w_.surfNodes[s];
            const int32_t ip = w_.nodePiece[n];
            const double r = w_.materials[w_.pieces[ip].material].radius;
            for (int d = 0; d < 3; ++d) {
                lo[3 * ip + d] = std::min(lo[3 * ip + d], w_.pos[3 * n + d] - r);
                hi[3 * ip + d] = std::max(hi[3 * ip + d], w_.pos[3 * n + d] + r);
            }
        }
        // With sleeping on, every rank decides which pieces sleep: they need
        // the same boxes (neighbour pieces, obstacles near), so the whole
        // pieces' boxes (one reduction).
        // So does the sphere coupling: which (sphere, piece) pairs may touch
        // sizes the reduction of their forces (SpherePhase::listActive), and
        // YADE's copy of the scene on each rank moves the proxies by them.
        if (w_.settings.sleepVelocity > 0 || !w_.spheres.pairPiece.empty()) {
            for (std::size_t i = 0; i < 3 * np; ++i) hi[i] = -hi[i];
            dom->comm().allreduceMin(lo.data(), static_cast<int>(3 * np));
            dom->comm().allreduceMin(hi.data(), static_cast<int>(3 * np));
            for (std::size_t i = 0; i < 3 * np; ++i) hi[i] = -hi[i];
        }
        return;
    }
    for (std::size_t ip = 0; ip < np; ++ip) {
        if (w_.sleeping.asleep(ip) && !all) continue;  // has not moved
        const PieceInfo& p = w_.pieces[ip];
        Eigen::Vector3d l = Eigen::Vector3d::Constant(1e300), h = -l;
        for (int32_t s = p.surfBegin; s < p.surfEnd; ++s) {
            const Eigen::Vector3d x(w_.pos[3 * w_.surfNodes[s]], w_.pos[3 * w_.surfNodes[s] + 1],
                                    w_.pos[3 * w_.surfNodes[s] + 2]);
            l = l.cwiseMin(x);
            h = h.cwiseMax(x);
        }
        const double r = w_.materials[p.material].radius;
        for (int d = 0; d < 3; ++d) {
            lo[3 * ip + d] = l[d] - r;
            hi[3 * ip + d] = h[d] + r;
        }
    }
}

}  // namespace qdem
