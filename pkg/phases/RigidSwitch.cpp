// Adaptive rigidity (settings.rigidify; RigidBodies.hpp): which pieces the
// awake set marks rigid, from the integration's indicators.  A deformable
// piece whose strain-rate estimate stayed below rigidStrainRate for
// rigidTime becomes rigid; a rigid one whose load changed by more than
// rigidWakeLoad (or rigidify off) becomes deformable again, going on from
// its rigid velocities and positions (no jump).  Sleeping has precedence:
// a piece that falls asleep is no longer rigid.
#include "IntegrationPhase.hpp"
#include "SleepPhase.hpp"

namespace qdem {

bool SleepPhase::switchRigid() {
    const RigidBodies& rb = w_.integration.rigid();
    bool changed = false;
    for (std::size_t p = 0; p < w_.pieces.size(); ++p) {
        const bool now = w_.awake.rigid_[p] != 0;
        const bool next = now ? !rb.wantsDeformable(p) : rb.wantsRigid(p);
        if (next == now) continue;
        w_.awake.rigid_[p] = next ? 1 : 0;
        ++rigidSwitches_;
        changed = true;
    }
    return changed;
}

}  // namespace qdem
