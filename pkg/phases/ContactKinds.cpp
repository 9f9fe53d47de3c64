// The table of piece-piece contact kinds (ContactKind.hpp).  YADE spheres
// against piece surfaces are the SpherePhase's (the spheres are YADE's
// bodies, not pieces): doc/architecture.md lists that kind beside these.
#include "ContactKind.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

namespace {

// The kernel of the seed's two kinds: the phase's point-polygon or edge-edge
// pass, with or without friction.
enum class SeedKind { PointPolygon, EdgeEdge };

template <SeedKind K>
class SeedKernel final : public ContactKind {
public:
    long run(KindStep& s) override {
        long n = 0;
        if constexpr (K == SeedKind::PointPolygon) {
            if (s.friction) s.phase.pointPolygon<true>(s.dt, s.eDamp, s.eSlip, n, s.maxOverlap);
            else s.phase.pointPolygon<false>(s.dt, s.eDamp, s.eSlip, n, s.maxOverlap);
        } else {
            if (s.friction) s.phase.edgeEdge<true>(s.dt, s.eDamp, s.eSlip, n, s.maxOverlap);
            else s.phase.edgeEdge<false>(s.dt, s.eDamp, s.eSlip, n, s.maxOverlap);
        }
        return n;
    }
};

std::unique_ptr<ContactKind> makePointPolygon() { return std::make_unique<SeedKernel<SeedKind::PointPolygon>>(); }
std::unique_ptr<ContactKind> makeEdgeEdge() { return std::make_unique<SeedKernel<SeedKind::EdgeEdge>>(); }

std::vector<ContactKindRow>& table() {
    static std::vector<ContactKindRow> rows = {
        {"pointPolygon",
         "surface triangles near other pieces (cell lists, Verlet lists of each surface node; the seed's cases "
         "A/B/C: tetrahedra)",
         "6 slots per surface node: other piece, 8 x local triangle + feature, tangential spring, born-deep "
         "reference",
         &Settings::pointPolygonOn, &makePointPolygon, RegisterSurfaceTriangles},
        {"edgeEdge", "feature edges near other pieces (box grids, Verlet lists of each registered edge)",
         "4 slots per surface edge (owned by the lower piece): other piece, local edge, side, tangential spring, "
         "born-deep reference",
         &Settings::edgeEdgeOn, &makeEdgeEdge, RegisterFeatureEdges},
    };
    return rows;
}

}  // namespace

const std::vector<ContactKindRow>& contactKinds() { return table(); }

void addContactKind(const ContactKindRow& row) { table().push_back(row); }

void removeContactKind(const std::string& name) {
    auto& t = table();
    for (auto it = t.begin(); it != t.end();)
        it = name == it->name ? t.erase(it) : it + 1;
}

}  // namespace qdem
