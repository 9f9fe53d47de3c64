// World::stableStepVersion: a number that changes when the stable step may
// have.  The settings are compared member by member from their one
// declaration (Settings.hpp's QDEM_SETTINGS), so a setting added there is
// covered without an edit here; bitwise, so a NaN compares equal to itself.
#include <cstring>

#include "world/World.hpp"

namespace qdem {

namespace {

bool sameSettings(const Settings& a, const Settings& b) {
    bool same = true;
#define QDEM_SAME_SETTING(T, name, engineName, def, range, doc) \
    same = same && std::memcmp(&a.name, &b.name, sizeof(T)) == 0;
    QDEM_SETTINGS(QDEM_SAME_SETTING)
#undef QDEM_SAME_SETTING
    return same;
}

}  // namespace

long World::stableStepVersion() const {
    if (inputSets_ != seenInputSets_ || pieces.size() != seenPieces_ || materials.size() != seenMaterials_ ||
        !sameSettings(settings, seenSettings_)) {
        ++stableStepVersion_;
        seenInputSets_ = inputSets_;
        seenPieces_ = pieces.size();
        seenMaterials_ = materials.size();
        seenSettings_ = settings;
    }
    return stableStepVersion_;
}

}  // namespace qdem
