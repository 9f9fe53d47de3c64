// Shared pieces of the contact phases (point-polygon, edge-edge, spheres):
// candidate records, history keys by stable ids, the born-deep rule.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "../contact/ContactLaw.hpp"
#include "../contact/ContactModel.hpp"
#include "../contact/Geometry.hpp"
#include "../core/Column.hpp"
#include "../material/Material.hpp"

namespace qdem::contact_detail {

using Eigen::Vector3d;

// The law's constants of two pieces' materials (ContactModel.hpp):
// computed once per step per neighbour pair, not per contact (a log and
// three square roots).
inline PairConst pairConst(const Material& a, const Material& b) {
    return mix(materialSide(a, a.frictionPiece), materialSide(b, b.frictionPiece));
}

// Contact parameters of two particles of materials a, b and masses ma, mb.
inline PairLaw pairLaw(const Material& a, const Material& b, double ma, double mb) {
    return pairLaw(pairConst(a, b), ma, mb);
}

inline Vector3d at(const Column<double>& c, int32_t i) { return Vector3d(c[3 * i], c[3 * i + 1], c[3 * i + 2]); }
// The same from a raw pointer hoisted out of a hot loop.
inline Vector3d at(const double* c, int32_t i) { return Vector3d(c[3 * i], c[3 * i + 1], c[3 * i + 2]); }

inline void addTo(double* buf, int32_t s, const Vector3d& f) {
    buf[3 * s] += f[0];
    buf[3 * s + 1] += f[1];
    buf[3 * s + 2] += f[2];
}

// Reference overlap of a contact (doc/contacts.md §5, "Contacts born deep").
// A contact carried from the previous step keeps its reference, lowered to
// the current overlap when the node has moved out past it (so it never pulls
// and never stores energy it was not given).  A new contact on a node that
// was already watched on the previous step, deeper than the reach plus what
// this step's approach can explain, was missed by the detection (a node
// beyond the search range), not made by a touch: it starts from its present
// overlap as reference, with no stored energy.  Normal contacts have 0 and
// get bit-for-bit the plain law.
inline double bornDeepRef(bool carried, double oldRef, bool watched, double overlap, double reach,
                          double vn, double dt) {
    if (carried) return std::min(oldRef, overlap);
    const double approach = vn < 0 ? -vn * dt : 0.0;
    return watched && overlap > reach + approach ? overlap - approach : 0.0;
}

// Contact history is keyed by stable ids: the other piece and, within it,
// 8 * (local triangle id) + closest feature (0 face, 1-3 edge, 4-6 corner),
// so a history survives any renumbering of the global arrays (pieces added,
// migrated to another process).  Local triangle t of piece p is global
// triangle SurfaceIndex::pieceTriStart[p] + t.
inline int32_t historyKey(int32_t localTri, TriFeature f) { return 8 * localTri + static_cast<int32_t>(f); }
inline int32_t historyTri(int32_t key) { return key >> 3; }

struct Candidate {
    int32_t tri;
    TriPoint cp;
    double dist;
    bool behind;
};

constexpr int kCandidates = 32;

// Mass and velocity of a candidate's closest point on triangle tn (the
// triangle nodes' values weighted by the point's barycentric weights).
inline void trianglePointState(const Candidate& c, const int32_t* tn, const Column<double>& mass,
                               const Column<double>& vel, double& m, Vector3d& v) {
    m = 0;
    v = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
        m += c.cp.w[k] * mass[tn[k]];
        v += c.cp.w[k] * at(vel, tn[k]);
    }
}

// Contact normal (towards the query point P) and overlap of a candidate at
// contact reach `reach`: a point behind the face is inside the other piece,
// so the normal points back out and the overlap grows past the reach.  nT,
// the face normal, stands in when P lies on the surface (dist <= eps).
inline void candidateContact(const Candidate& c, const Vector3d& P, const Vector3d& nT, double reach, double eps,
                             Vector3d& n, double& overlap) {
    if (c.behind) {
        n = c.dist > eps ? Vector3d((c.cp.point - P) / c.dist) : nT;
        overlap = reach + c.dist;
    } else {
        n = c.dist > eps ? Vector3d((P - c.cp.point) / c.dist) : nT;
        overlap = reach - c.dist;
    }
}

}  // namespace qdem::contact_detail
