// Inverted elements are never carried silently (issue 12): counted every
// check period; a law that cannot push them back stops the run.  So does a
// node sunk into another piece beyond the contact reach (checkDeepOverlap,
// the scan in pkg/phases/PieceStartOverlap.cpp).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../contact/Geometry.hpp"
#include "../contact/WindingNumber.hpp"
#include "../element/MaterialLaw.hpp"
#include "Phases.hpp"
#include "World.hpp"

namespace qdem {

InversionCount World::countInverted() const {
    requireGathered("countInverted");
    InversionCount r;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (asleep(i)) continue;  // does not move: counted while it was awake
        const PieceInfo& p = pieces[i];
        for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) {
            const int32_t* c = &tetNodes[4 * e];
            // J = det(Ds B) = det(Ds) det(B); det(B) = 1/(6 V0) > 0 for the
            // positively oriented reference tets addPiece accepts.
            const Mat3 Ds = edgeMatrix(&pos[3 * c[0]], &pos[3 * c[1]], &pos[3 * c[2]], &pos[3 * c[3]]);
            const double det = Ds.determinant();
            if (!(det <= 0)) continue;  // (NaN: checkFinite's business)
            // (Each element's own law: a bonded piece has several.)
            const bool recovers = withLaw(tetMat(e), [](const auto& law) {
                return std::decay_t<decltype(law)>::kRecoversFromInversion;
            });
            ++r.count;
            if (!recovers) ++r.unrecoverable;
            const bool first = r.count == 1 || (!recovers && r.unrecoverable == 1);
            if (first) {  // the first inverted element; an unrecoverable one takes precedence
                r.piece = static_cast<int>(i);
                r.element = e - p.tetBegin;
                r.volumeRatio = det / (6.0 * tetVol0[e]);
            }
        }
    }
    return r;
}

InversionCount World::checkInverted() const {
    const InversionCount r = countInverted();
    if (r.unrecoverable > 0)
        throw StabilityError(cat(
            "QDEM: at step ", iter, " (t=", time, " s) tetrahedron ", r.element, " of piece ", r.piece,
            " is inverted (volume ratio ", r.volumeRatio, "; ", r.unrecoverable, " inverted element(s) in all): a ",
            "Saint-Venant-Kirchhoff element compressed past its limit point (stretch 1/sqrt(3)) snaps through and "
            "stays inverted, which this law cannot undo. Use law='stableNeoHookean' (the default), a stiffer "
            "material or a smaller impact speed."));
    return r;
}

void World::checkDeepOverlap() {
    requireGathered("checkDeepOverlap");
    std::string error;
    try {
        phases_->pieceContact.checkDeepOverlap(iter, time);
    } catch (const StabilityError& e) {
        error = e.what();
    }
    error = agreeOnError(error);  // (the ranks' start-overlap exemptions are their own nodes')
    if (!error.empty()) throw StabilityError(error);
}

void World::checkSpheresInside() const {
    requireGathered("checkSpheresInside");
    const SphereSet& S = spheres;
    const std::size_t ns = S.id.size();
    if (ns == 0 || pieces.empty()) return;
    const SurfaceIndex& surf = surfaceIndex();
    // Each piece's box from its nodes (the same on every rank: all gathered).
    std::vector<double> lo(3 * pieces.size(), 1e300), hi(3 * pieces.size(), -1e300);
    for (std::size_t p = 0; p < pieces.size(); ++p)
        for (int32_t n = pieces[p].nodeBegin; n < pieces[p].nodeEnd; ++n)
            for (int d = 0; d < 3; ++d) {
                lo[3 * p + d] = std::min(lo[3 * p + d], pos[3 * n + d]);
                hi[3 * p + d] = std::max(hi[3 * p + d], pos[3 * n + d]);
            }
    std::string error;
    for (std::size_t i = 0; i < ns && error.empty(); ++i) {
        const Eigen::Vector3d c(S.pos[3 * i], S.pos[3 * i + 1], S.pos[3 * i + 2]);
        for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1] && error.empty(); ++q) {
            const int32_t p = S.pairPiece[q];
            bool inBox = true;
            for (int d = 0; d < 3; ++d) inBox = inBox && lo[3 * p + d] < c[d] && c[d] < hi[3 * p + d];
            if (!inBox) continue;
            const int32_t t0 = surf.pieceTriStart[p], t1 = surf.pieceTriStart[p + 1];
            if (!(windingNumber(c, surf.tri.data(), t0, t1, pos.data()) > 0.5)) continue;
            double depth = 1e300;
            for (int32_t t = t0; t < t1; ++t) {
                const int32_t* k = &surf.tri[3 * t];
                const TriPoint cp = closestOnTriangle(c, Eigen::Map<const Eigen::Vector3d>(&pos[3 * k[0]]),
                                                      Eigen::Map<const Eigen::Vector3d>(&pos[3 * k[1]]),
                                                      Eigen::Map<const Eigen::Vector3d>(&pos[3 * k[2]]));
                depth = std::min(depth, (c - cp.point).norm());
            }
            const double r = materials[pieces[p].material].radius, reach = S.radius[i] + r;
            if (depth <= reach) continue;  // in the contact's range: pushed out
            error = cat("QDEM: YADE sphere #", S.id[i], " (radius ", S.radius[i], " m) is inside piece ", p,
                        ", its centre ", depth, " m below the piece's surface, beyond the contact's reach (sphere "
                        "radius + node radius = ", reach, " m): nothing pushes it out, and it would stay there or "
                        "sink on. Either it was placed inside the piece (place it outside), or its contact was too "
                        "soft for its load or impact (its material's young = ", S.young[i],
                        " Pa gives a contact stiffness young x radius = ", S.young[i] * S.radius[i],
                        " N/m): give the sphere a stiffer material, or slow it down (doc/spheres.md)");
        }
    }
    error = agreeOnError(error);
    if (!error.empty()) throw StabilityError(error);
}

}  // namespace qdem
