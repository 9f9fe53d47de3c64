// Working data of the piece-piece contact phase (PieceContactPhase).  Everything
// here is sized once and reused, so the step does not allocate.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../contact/BoxGrid.hpp"
#include "../contact/ContactLaw.hpp"
#include "../contact/CellGrid.hpp"
#include "../contact/SurfaceIndex.hpp"
#include "../step/Settings.hpp"

namespace qdem {

struct PieceContactState {
    SurfaceIndex surf;
    // Per piece: a cell list of its registered surface elements, so a query
    // from one piece visits only the other pieces' elements.
    std::vector<CellGrid> itemGrid;
    std::vector<BoxGrid> edgeGrid;
    // CSR per piece: registered triangle or tet ids, itemStart[np] of them
    // (the arrays keep room for every candidate: no refill per rebuild).
    std::vector<int32_t> itemStart, items;
    std::vector<double> itemPoint;              // their reference points (3 each)
    std::vector<double> itemRadius;             // and bounding radii about them
    std::vector<int32_t> edgeStart, edgeItems;  // CSR per piece: registered edge ids, edgeStart[np] of them
    int32_t registeredEdges() const { return edgeStart.empty() ? 0 : edgeStart.back(); }
    // Per registered edge, what edge-edge reads of the other edge of a pair:
    // its two nodes, its piece and its id within that piece (kEdgeRec each,
    // 16 bytes), one load where the surface index took three dependent ones.
    static constexpr int kEdgeRec = 4;
    std::vector<int32_t> edgeRec;
    std::vector<double> edgeLo, edgeHi;         // their boxes grown by half the contact reach (3 each)
    double itemReach = 0;                       // largest bounding radius + contact reach
    // Per step, per triangle: unit outward normal (3), for the quick plane test.
    std::vector<double> triNormal;
    // Per step, per surface node: the spin of the surface there (3, rad/s;
    // SurfaceSpin.hpp), by which piece-piece springs turn; filled with
    // friction on, for the nodes of active pieces (under MPI the current ones).
    std::vector<double> surfSpin;
    std::vector<uint8_t> spinPiece;  // per piece: its surface spins are computed this step

    // Verlet lists (default broad phase): per surface node, the triangles of
    // other pieces within reach + skin at the last rebuild.  Valid until some
    // surface node has moved more than skin/2 since then (two nodes closing
    // in on each other then still cannot have crossed the skin).
    static constexpr int kList = 48;
    std::vector<int32_t> listCount;  // per surface node; -1 = overflow, query the cells instead
    // The lists packed chunk by chunk: node i's triangles are
    // listFlat[listStart[i] .. listStart[i] + listCount[i]); the lists of a
    // chunk of kListChunk nodes follow one another in the chunk's stretch of
    // kListChunk * kList entries, so the step reads them as one stream per
    // chunk, and the build writes them there with no packing pass.
    static constexpr int32_t kListChunk = 64;
    std::vector<int32_t> listStart, listFlat;
    std::vector<double> listPos;     // surface node positions at the rebuild (3 each)
    // A rebuild spread over steps (settings.verletRebuildSteps, doc/contacts.md
    // "Verlet lists"): its first step registers and bins the surface
    // triangles, the second the feature edges (with their lists), and the
    // steps after the first build the nodes' lists chunk by chunk, into the
    // other half of listFlat, while the nodes not yet done go on with their
    // former lists.  Those stay valid while no surface node has moved
    // more than skin/2 - listSlackOld from listPosOld (their reference); the
    // new lists while none has moved more than skin/2 - listSlack from
    // listPos, where listSlack is the largest such move at any of their
    // chunks' builds (lists built a few steps after their reference).
    std::vector<double> listPosOld;
    double listSlack = 0, listSlackOld = 0;
    int32_t windowNext = -1;         // next chunk of an open window (-1: none open)
    int32_t windowChunksPerStep = 0;
    bool windowEdgesPending = false; // the window's edges are registered on its second step
    int listHalf = 0;                // the half of listFlat the newest lists are in
    double lastMoved = -1;           // the largest move from listPos at the last step (-1: lists new)
    long windowSteps = 0;            // steps that built node lists after their window's first
    std::vector<uint8_t> listActive; // pieces active at the rebuild
    double listSkin = 0;
    std::size_t listTris = 0;        // triangle count at the rebuild (pieces added: rebuild)
    bool listValid = false;
    // The registrations (ContactKind.hpp bits) the last rebuild made.  A kind
    // switched on since has nothing of its own registered (edge-edge found
    // no edges until some node moved half the skin: in a still scene,
    // never), so a change forces a rebuild.
    unsigned listKinds = 0;
    long listBuilds = 0;
    // The same for feature edges: per registered edge, registered edges of
    // higher pieces whose (skin-grown) boxes overlapped at the rebuild.
    static constexpr int kEdgeList = 32;
    std::vector<int32_t> edgeList, edgeListCount;
    std::vector<uint8_t> pieceActive;  // piece has a neighbour piece within reach
    std::vector<int32_t> nbrStart, nbrs;   // CSR: the pieces whose boxes overlap each piece's
    std::vector<int32_t> pieceOrder, pairs, nbrFill;  // sweep-and-prune work arrays
    std::vector<double> nbrBox;  // per nbrs entry (list rebuilds): reach + skin, the neighbour's box lo, hi (7 arrays)

    // Does the box [lo, hi] touch the box of a piece that piece pa can reach?
    // (pieceLo, pieceHi: the pieces' boxes, PieceBounds::lo/hi.)  `hint`: the
    // neighbour entry that answered the caller's previous question (-1: none),
    // tested first and updated on a hit.  Consecutive elements of a surface
    // mostly lie near the same neighbour, so one test usually answers, where
    // the scan in order meets the corner and edge neighbours first (a branch
    // mispredicted per miss); the answer is the scan's either way.
    bool nearOther(int32_t pa, const double* lo, const double* hi, const double* pieceLo, const double* pieceHi,
                   int32_t& hint) const {
        auto overlaps = [&](int32_t q) {
            const int32_t pb = nbrs[q];
            bool overlap = true;
            for (int d = 0; d < 3 && overlap; ++d)
                overlap = lo[d] <= pieceHi[3 * pb + d] && pieceLo[3 * pb + d] <= hi[d];
            return overlap;
        };
        if (hint >= nbrStart[pa] && hint < nbrStart[pa + 1] && overlaps(hint)) return true;
        for (int32_t q = nbrStart[pa]; q < nbrStart[pa + 1]; ++q)
            if (q != hint && overlaps(q)) {
                hint = q;
                return true;
            }
        return false;
    }
    std::vector<std::vector<double>> threadForce;  // per thread, 3 per surface node
    std::vector<const double*> threadForceData;    // their data(), for the sum's inner loop
    // Per thread, 2 per surface node: the contacts' stiffness and dashpot
    // load on it (ContactLoad.hpp), zeroed and summed with the forces.
    std::vector<std::vector<double>> threadLoad;
    std::vector<const double*> threadLoadData;
    // Per step: the law's material constants of each neighbour pair (one per
    // nbrs entry) and each piece's particle radius, so the narrow phase takes
    // no log or root per contact.
    std::vector<PairConst> nbrLaw;
    std::vector<double> pieceRadius;
    // (The contact histories are the kinds': PointPolygonKind.hpp, EdgeEdgeKind.hpp.)
};

}  // namespace qdem
