// The world's phases built from its members (Phases.hpp), and what the
// World hands out of them.
#include "Phases.hpp"

#include "../phases/PointPolygonKind.hpp"

#include "World.hpp"

namespace qdem {

WorldPhases::WorldPhases(World& w)
    : obstacle{{.pos = w.pos, .vel = w.vel, .refPos = w.refPos, .mass = w.mass, .nodePiece = w.nodePiece,
                .surfNodes = w.surfNodes, .surfWeight = w.surfWeight, .pieces = w.pieces, .materials = w.materials,
                .settings = w.settings, .sleeping = w.awake_, .bounds = w.bounds_, .obstacles = w.obstacles,
                .contacts = w.contactForces_, .energy = w.energy, .threadPieceEnergy = w.threadPieceEnergy_,
                .iter = w.iter}},
      pieceContact{{.pos = w.pos, .vel = w.vel, .refPos = w.refPos, .mass = w.mass, .nodePiece = w.nodePiece,
                    .tetNodes = w.tetNodes, .surfNodes = w.surfNodes, .surfWeight = w.surfWeight, .pieces = w.pieces,
                    .materials = w.materials, .settings = w.settings, .iter = w.iter, .surface = w.surf_,
                    .sleeping = w.awake_, .bounds = w.bounds_, .domain = {w.domain_}, .contacts = w.contactForces_,
                    .energy = w.energy, .threadPieceEnergy = w.threadPieceEnergy_,
                    .pieceElementW2 = w.pieceElementW2_, .pieceElementRate = w.pieceElementRate_}},
      sphere{{.pos = w.pos, .vel = w.vel, .mass = w.mass, .surfNodes = w.surfNodes, .pieces = w.pieces,
              .materials = w.materials, .settings = w.settings, .iter = w.iter, .surface = w.surf_,
              .bounds = w.bounds_, .domain = {w.domain_}, .spheres = w.spheres, .contacts = w.contactForces_,
              .energy = w.energy}},
      element{{.pos = w.pos, .vel = w.vel, .tetNodes = w.tetNodes, .tetPiece = w.tetPiece, .tetB = w.tetB,
               .tetVol0 = w.tetVol0, .tetMaterial = w.tetMaterial, .pieces = w.pieces, .materials = w.materials, .settings = w.settings,
               .sleeping = w.awake_, .energy = w.energy, .threadPieceEnergy = w.threadPieceEnergy_}},
      integration{{.mass = w.mass, .extForce = w.extForce, .blocked = w.blocked, .nodePiece = w.nodePiece,
                   .pieces = w.pieces, .gravity = w.gravity, .settings = w.settings, .sleeping = w.awake_,
                   .elements = element, .contacts = w.contactForces_, .domain = {w.domain_}, .pos = w.pos,
                   .vel = w.vel, .force = w.force, .energy = w.energy, .iter = w.iter, .time = w.time,
                   .viscous = {.pos = w.pos, .refPos = w.refPos, .mass = w.mass, .blocked = w.blocked, .tetNodes = w.tetNodes,
                               .tetB = w.tetB, .tetVol0 = w.tetVol0, .tetMaterial = w.tetMaterial, .pieces = w.pieces, .materials = w.materials,
                               .settings = w.settings, .iter = w.iter, .sleeping = w.awake_,
                               .domain = {w.domain_}}}},
      sleep{{.pos = w.pos, .vel = w.vel, .mass = w.mass, .blocked = w.blocked, .surfNodes = w.surfNodes,
             .pieces = w.pieces, .obstacles = w.obstacles, .spheres = w.spheres, .settings = w.settings,
             .gravity = w.gravity, .domain = {w.domain_}, .energy = w.energy, .bounds = w.bounds_,
             .awake = w.awake_, .obstacleContacts = obstacle, .pieceContacts = pieceContact,
             .integration = integration, .force = w.force}} {}

World::World() : phases_(std::make_unique<WorldPhases>(*this)) {}
World::~World() = default;

const std::array<Phase*, 6>& World::phases() { return phases_->list; }
std::array<const Phase*, 6> World::phases() const {
    const std::array<Phase*, 6>& p = phases_->list;
    return {p[0], p[1], p[2], p[3], p[4], p[5]};
}

void World::setSpheres(int32_t n, const int32_t* id, const double* radius, const double* young,
                       const double* ktRatio, const double* friction, const double* restitution,
                       const double* sphereMass, const int32_t* pairStart, const int32_t* pairPiece) {
    phases_->sphere.setSpheres(n, id, radius, young, ktRatio, friction, restitution, sphereMass, pairStart,
                               pairPiece);
    ++inputSets_;
}

std::vector<std::string> World::takeStartWarnings() {
    std::vector<std::string> w = phases_->obstacle.takeStartWarnings();
    for (std::string& m : phases_->pieceContact.takeStartWarnings()) w.push_back(std::move(m));
    return w;
}

void World::computeStress(double* out) const {
    requireGathered("computeStress");
    phases_->element.stress(out);
}

long World::sleepCount() const { return phases_->sleep.sleepCount(); }
long World::wakeCount() const { return phases_->sleep.wakeCount(); }
void World::wake(std::size_t piece) { phases_->sleep.wake(piece); }
long World::rigidSwitches() const { return phases_->sleep.rigidSwitches(); }
double World::strainRateEstimate(std::size_t piece) const { return phases_->integration.rigid().strainRate(piece); }
double World::rigidLoadChange(std::size_t piece) const { return phases_->integration.rigid().loadChange(piece); }
double World::rigidLoadStrain(std::size_t piece) const { return phases_->integration.rigid().loadStrain(piece); }
void World::wakeAll() { phases_->sleep.wakeAll(); }

PhaseReport World::report() const {
    PhaseReport r;
    for (const Phase* p : phases()) p->report(r);
    return r;
}

long World::verletRebuilds() const { return phases_->pieceContact.state().listBuilds; }
long World::verletWindowSteps() const { return phases_->pieceContact.state().windowSteps; }
bool World::verletWindowOpen() const { return phases_->pieceContact.state().windowNext >= 0; }
const PieceContactState& World::pieceContactState() const { return phases_->pieceContact.state(); }
const Column<int32_t>& World::pointPolygonKeys() const {
    return static_cast<const PointPolygonKind*>(phases_->pieceContact.kind("pointPolygon"))->keys();
}
const Column<int32_t>& World::pointPolygonKeyPieces() const {
    return static_cast<const PointPolygonKind*>(phases_->pieceContact.kind("pointPolygon"))->keyPieces();
}
double World::maxPieceOverlap() const { return phases_->pieceContact.maxOverlap(); }
double World::maxPieceDepthRatio() const { return phases_->pieceContact.maxDepthRatio(); }

}  // namespace qdem
