// The table of piece-piece contact kinds (ContactKind.hpp).  YADE spheres
// against piece surfaces are the SpherePhase's (the spheres are YADE's
// bodies, not pieces): doc/architecture.md lists that kind beside these.
#include "ContactKind.hpp"
#include "EdgeEdgeKind.hpp"
#include "PointPolygonKind.hpp"

namespace qdem {

std::unique_ptr<ContactKind> makeNodeSpringKind();  // NodeSpringKind.cpp (test-only)

namespace {

template <class Kind>
std::unique_ptr<ContactKind> make() {
    return std::make_unique<Kind>();
}

std::vector<ContactKindRow>& table() {
    static std::vector<ContactKindRow> rows = {
        {"pointPolygon",
         "surface triangles near other pieces (cell lists, Verlet lists of each surface node; the seed's cases "
         "A/B/C: tetrahedra)",
         "6 slots per surface node: other piece, 8 x local triangle + feature, tangential spring, born-deep "
         "reference",
         &Settings::pointPolygonOn, &make<PointPolygonKind>, RegisterSurfaceTriangles},
        {"edgeEdge", "feature edges near other pieces (box grids, Verlet lists of each registered edge)",
         "4 slots per surface edge (owned by the lower piece): other piece, local edge, side, tangential spring, "
         "born-deep reference",
         &Settings::edgeEdgeOn, &make<EdgeEdgeKind>, RegisterFeatureEdges},
        {"nodeSpringTest", "nothing (surface nodes of neighbour pieces, all pairs)",
         "4 slots per surface node: other piece, its surface node, rest length", &Settings::nodeSpringTestOn,
         &makeNodeSpringKind, RegisterNothing},
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
