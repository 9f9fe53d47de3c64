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
    // The contact springs and dashpots on each surface node this step, 2 per
    // surface node (stiffness [N/m], dashpot [N s/m]; ContactLoad.hpp): the
    // obstacle, piece-contact and sphere phases add their shares, the
    // run-time stable step reads the sums (PieceContactPhase::stepLimit).
    std::vector<double> load;
    bool loadActive = false;  // load holds this step's shares (else it is stale)
    // A new step: nothing added yet.
    void reset() { active = loadActive = false; }
    // Before the first share of a step: every row to zero (16 bytes per
    // surface node, once per step).  Returns the rows.
    double* beginLoad() {
        if (!loadActive) load.assign(2 * surfNodes_.size(), 0.0), loadActive = true;
        return load.data();
    }
    // Before the first addition of a step: the awake pieces' surface nodes to
    // zero (a sleeping piece is not integrated: its forces are not read).
    void begin();

private:
    const std::vector<PieceInfo>& pieces_;
    const Column<int32_t>& surfNodes_;
    const AwakeSet& sleeping_;
};

}  // namespace qdem
