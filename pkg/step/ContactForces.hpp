// The contact forces on nodes of one step: the obstacle, piece-contact and
// sphere phases add into them, the integration reads them.  Zeroed once per
// step, by the first phase that adds (a scene without contacts never pays).
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../mesh/PieceInfo.hpp"
#include "AwakeSet.hpp"

namespace qdem {

class ContactForces {
public:
    ContactForces(const std::vector<PieceInfo>& pieces, const Column<int32_t>& surfNodes, const AwakeSet& sleeping)
        : pieces_(pieces), surfNodes_(surfNodes), sleeping_(sleeping) {}
    Column<double> force;  // 3 per node
    bool active = false;   // force holds this step's contacts (else the integration skips it)
    // A new step: nothing added yet.
    void reset() { active = false; }
    // Before the first addition of a step: the awake pieces' surface nodes to
    // zero (a sleeping piece is not integrated: its forces are not read).
    void begin();

private:
    const std::vector<PieceInfo>& pieces_;
    const Column<int32_t>& surfNodes_;
    const AwakeSet& sleeping_;
};

}  // namespace qdem
