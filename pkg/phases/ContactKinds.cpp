// The table of contact kinds (ContactKind.hpp): between pieces (run by
// PieceContactPhase), surface nodes against YADE obstacles (ObstaclePhase)
// and YADE spheres against piece surfaces (SpherePhase).
#include "ContactKind.hpp"
#include "EdgeEdgeKind.hpp"
#include "PointPolygonKind.hpp"

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "PieceContactPhase.hpp"

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
        {"wall", "YADE walls, boxes and facets near each piece (bounding boxes grown by the node radius)",
         "4 slots per surface node: YADE body id, side, tangential spring",
         &Settings::obstaclesOn, nullptr, RegisterNothing, ContactFamily::PieceObstacle},
        {"sphere", "YADE spheres near each piece (YADE's collider, through proxy bodies), the piece's surface "
         "triangles binned per step",
         "4 slots per (sphere, piece) pair: 8 x local triangle + feature, tangential spring, born-deep reference",
         &Settings::spheresOn, nullptr, RegisterNothing, ContactFamily::PieceSphere},
        {"nodeSpringTest", "nothing (surface nodes of neighbour pieces, all pairs)",
         "4 slots per surface node: other piece, its surface node, rest length", &Settings::nodeSpringTestOn,
         &makeNodeSpringKind, RegisterNothing},
    };
    return rows;
}

}  // namespace

const std::vector<ContactKindRow>& contactKinds() { return table(); }

const ContactKindRow& contactKind(ContactFamily family) {
    for (const ContactKindRow& row : table())
        if (row.family == family) return row;
    throw InputError("contact kinds: no row of this family (internal error)");
}

void addContactKind(const ContactKindRow& row) {
    if (row.family != ContactFamily::PiecePiece || !row.make)
        throw InputError(cat("addContactKind: '", row.name, "' must be a piece-piece kind with a kernel (make); ",
                             "obstacles and spheres have one kind each, run by their phases"));
    table().push_back(row);
}

void removeContactKind(const std::string& name) {
    auto& t = table();
    for (auto it = t.begin(); it != t.end();)
        it = name == it->name ? t.erase(it) : it + 1;
}

}  // namespace qdem
