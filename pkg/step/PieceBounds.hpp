// Per piece, the box of its surface nodes grown by its particle radius:
// where the piece can touch anything this step (obstacles, other pieces,
// spheres).  Updated at the start of each step for the awake pieces.
#pragma once
#include <cstdint>
#include <vector>

#include "../contact/SphereSet.hpp"
#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../parallel/DomainRef.hpp"
#include "../mesh/PieceInfo.hpp"
#include "AwakeSet.hpp"
#include "Settings.hpp"

namespace qdem {

class PieceBounds {
public:
    struct Data {
        const Column<double>& pos;
        const Column<int32_t>& surfNodes;
        const Column<int32_t>& nodePiece;
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const AwakeSet& sleeping;
        const SphereSet& spheres;  // coupled spheres: the whole pieces' boxes under MPI
        DomainRef domain;
    };
    explicit PieceBounds(Data data) : w_(data) {}
    std::vector<double> lo, hi;  // 3 per piece
    // The awake pieces' boxes (all: the sleeping ones' too, after a load or
    // when a piece is held).  Under MPI: from this rank's current nodes, the
    // whole pieces' boxes (one reduction) when sleeping is on.
    void update(bool all = false);

private:
    Data w_;
};

}  // namespace qdem
