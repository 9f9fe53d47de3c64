// The table of piece-piece contact kinds (ContactKind.hpp).  YADE spheres
// against piece surfaces are the SpherePhase's (the spheres are YADE's
// bodies, not pieces): doc/architecture.md lists that kind beside these.
#include "ContactKind.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

namespace {

std::vector<ContactKindRow>& table() {
    static std::vector<ContactKindRow> rows = {
        {"pointPolygon",
         "surface triangles near other pieces (cell lists, Verlet lists of each surface node; the seed's cases "
         "A/B/C: tetrahedra)",
         "6 slots per surface node: other piece, 8 x local triangle + feature, tangential spring, born-deep "
         "reference",
         &Settings::pointPolygonOn, &PieceContactPhase::makePointPolygonKind},
        {"edgeEdge", "feature edges near other pieces (box grids, Verlet lists of each registered edge)",
         "4 slots per surface edge (owned by the lower piece): other piece, local edge, side, tangential spring, "
         "born-deep reference",
         &Settings::edgeEdgeOn, &PieceContactPhase::makeEdgeEdgeKind},
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
