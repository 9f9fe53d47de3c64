// Inverted elements are never carried silently (issue 12): counted every
// check period; a law that cannot push them back stops the run.  So does a
// node sunk into another piece beyond the contact reach (checkDeepOverlap,
// the scan in pkg/phases/PieceStartOverlap.cpp).
#include <cmath>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/MaterialLaw.hpp"
#include "World.hpp"

namespace qdem {

InversionCount World::countInverted() const {
    requireGathered("countInverted");
    InversionCount r;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (asleep(i)) continue;  // does not move: counted while it was awake
        const PieceInfo& p = pieces[i];
        const bool recovers = withLaw(materials[p.material], [](const auto& law) {
            return std::decay_t<decltype(law)>::kRecoversFromInversion;
        });
        for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) {
            const int32_t* c = &tetNodes[4 * e];
            // J = det(Ds B) = det(Ds) det(B); det(B) = 1/(6 V0) > 0 for the
            // positively oriented reference tets addPiece accepts.
            const Mat3 Ds = edgeMatrix(&pos[3 * c[0]], &pos[3 * c[1]], &pos[3 * c[2]], &pos[3 * c[3]]);
            const double det = Ds.determinant();
            if (!(det <= 0)) continue;  // (NaN: checkFinite's business)
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
        pieceContactPhase_.checkDeepOverlap(iter, time);
    } catch (const StabilityError& e) {
        error = e.what();
    }
    error = agreeOnError(error);  // (the ranks' start-overlap exemptions are their own nodes')
    if (!error.empty()) throw StabilityError(error);
}

}  // namespace qdem
