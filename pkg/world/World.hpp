// The QDEM world: every piece's nodes and tetrahedra in shared struct-of-
// arrays storage, the rigid obstacles they touch, and the step pipeline.
//
// One step (World::step, WorldStep.cpp) runs the phases of pkg/phases in
// order: obstacles, piece contacts, spheres, elements, integration, sleep
// (doc/architecture.md), held in a WorldPhases (Phases.hpp) that only the
// world's own sources see.  Each phase runs only when the scene needs it (no viscous term for a piece
// with viscosity 0, no friction work at friction 0, no obstacle loop without
// obstacles, no energy sums unless tracked).
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "../contact/Obstacle.hpp"
#include "../contact/SurfaceIndex.hpp"
#include "../contact/SphereSet.hpp"
#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../mesh/Surface.hpp"
#include "../mesh/TetMesh.hpp"
#include "../parallel/Communicator.hpp"
#include "../parallel/Partition.hpp"
#include "../step/AwakeSet.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../step/PieceBounds.hpp"
#include "../mesh/PieceInfo.hpp"
#include "StepReport.hpp"
#include "../step/Settings.hpp"
#include "../parallel/ThreadLayout.hpp"
#include "../step/WorldState.hpp"

namespace qdem {

class Domain;
struct PieceContactState;
struct WorldPhases;

// Stable time step and which limit sets it.
struct StableDt {
    double elastic;   // undamped P-wave limit of the stiffest element
    double viscous;   // the same mode with its Kelvin-Voigt damping
    double contact;   // node-obstacle spring-dashpot, stiffest w kn / m over the surface nodes
    double combined;  // all of the above acting on one node: the step we enforce
    std::string limitedBy;
    // The combined step with the viscous force integrated explicitly, and
    // implicitly (settings.viscousIntegration): `combined` is one of them.
    double combinedExplicit, combinedImplicit;
    // The stiffest dynamic YADE obstacle (a Box, Facet or Wall YADE moves) on
    // the contact springs that can act on it, and its index in obstacles (-1:
    // none): already in contact and combined.
    double obstacle = std::numeric_limits<double>::infinity();
    int obstacleIndex = -1;
    // The piece whose elements set the element step (-1: no piece), as
    // PieceStepReport says (StepReport.cpp): its smallest-step elements in
    // its own numbering (tetIds), how many lie within 2x of the limit and
    // their worst quality (min height / longest edge), and the steps its
    // median element allows undamped and with viscosity.
    int piece = -1;
    std::vector<int32_t> elements{};
    int64_t elementsNearLimit = 0;
    double worstQuality = std::numeric_limits<double>::quiet_NaN();
    double pieceElastic = std::numeric_limits<double>::infinity(), pieceViscous = pieceElastic;
    double medianElastic = std::numeric_limits<double>::infinity(), medianViscous = medianElastic;
    // The piece-piece contacts of the last step as they act on each node,
    // with its piece's elements (ContactLoad.hpp; infinite: none), and where:
    // already in `combined`.
    double pieceContact = std::numeric_limits<double>::infinity();
    int32_t pieceContactNode = -1, pieceContactPiece = -1;
    long pieceContactStep = -1;
};

// An obstacle edge found crossing a piece's surface by World::obstacleEdgeCrossing.
struct ObstacleEdgeCrossing {
    int64_t count = 0;   // (edge, surface triangle) crossings
    int obstacle = -1;   // the first one: obstacle index, its YADE body, the piece, where
    int bodyId = -1;
    int piece = -1;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

// Inverted elements found by World::countInverted.
struct InversionCount {
    int64_t count = 0;            // elements with J <= 0
    int64_t unrecoverable = 0;    // of them, in pieces whose law cannot push them back
    int piece = -1;               // the first one: piece, its local element, its J
    int32_t element = -1;
    double volumeRatio = 1;
};

// What World::periodicChecks did at one step.
struct PeriodicChecks {
    bool ran = false;          // the checks were due at this step (and passed)
    InversionCount inverted;   // checkInverted's count (elements whose law pushes them back)
    ObstacleEdgeCrossing edges;  // obstacleEdgeCrossing's finding (Box and Facet edges through surfaces)
};

class World {
public:
    // ---- set-up -----------------------------------------------------------
    int addMaterial(const Material& m);
    // Adds a checked mesh whose coordinates are already in the world frame.
    // tetAddedMass (empty, or one value per tet, kg >= 0): mass added to each
    // element on top of rho V, a quarter to each of its nodes (selective mass
    // scaling, MassScaling.cpp); real mass, which gravity and contacts see.
    //
    // tetMaterial (empty, or one material index per tet): a bonded piece of
    // several materials, each element taking its own (doc/meshes.md, "Regions
    // and bimaterial parts"); `material` is then the piece's contact material
    // (radius, friction, restitution and the contact stiffness of its surface
    // nodes).  Tets of one material are best given contiguous: the element
    // phase computes blocks of one material (ThreadBlocks.hpp).
    int addPiece(const TetMesh& mesh, int material, const std::vector<double>& tetAddedMass = {},
                 const std::vector<int32_t>& tetMaterial = {});
    // Selective mass scaling (MassScaling.cpp, doc/meshes.md): per tet of
    // `mesh` (world coordinates, as addPiece takes it) the least mass to add
    // so that the element's own stable step, elastic and with the material's
    // Kelvin-Voigt viscosity, reaches targetDt by the test stableDt() makes:
    // 0 for the elements that reach it already.
    std::vector<double> massScaling(const TetMesh& mesh, int material, double targetDt) const;
    // The step the contact springs of piece i allow against a rigid wall
    // (its stiffest surface node), with and without its element springs on
    // the same node: what no mass added to slivers raises (MassScaling.cpp).
    void rigidContactLimit(std::size_t piece, double& contact, double& combined) const;
    // Pieces asleep are woken only when the list differs from the last one
    // (or from the one of a loaded state) in kind, body, material or shape: the
    // reactions they keep are by obstacle index.
    void setObstacles(const std::vector<Obstacle>& obstacles);
    // Copies one obstacle's state (from YADE) for the coming step; spinCentre:
    // its clump's centre for a clump member, else pos (Obstacle::velocityAt).
    void setObstacleState(int i, const Eigen::Vector3d& pos, const Eigen::Quaterniond& ori,
                          const Eigen::Vector3d& vel, const Eigen::Vector3d& angVel,
                          const Eigen::Vector3d& spinCentre);
    void setObstacleState(int i, const Eigen::Vector3d& p, const Eigen::Quaterniond& q, const Eigen::Vector3d& v,
                          const Eigen::Vector3d& w) {
        setObstacleState(i, p, q, v, w, p);
    }
    // The YADE spheres that may touch pieces (n of them; per-sphere arrays of
    // n, pairStart of n+1 and pairPiece of pairStart[n]: see SphereSet).
    // Contact history is carried over for (sphere id, piece) pairs kept.
    void setSpheres(int32_t n, const int32_t* id, const double* radius, const double* young, const double* ktRatio,
                    const double* friction, const double* restitution, const double* sphereMass, const int32_t* pairStart,
                    const int32_t* pairPiece);

    // ---- stepping ---------------------------------------------------------
    void step(double dt);
    // Throws StabilityError (naming the limit) when dt exceeds the stable step.
    void checkDt(double dt) const;
    StableDt stableDt() const;
    // beta = eta / mu of piece i's elements for the stable step: its
    // material's, or for a piece of several materials the largest damping
    // rate of an element over the largest omega^2 (pieceRateMax_): the
    // stiffest element's frequency with the most damped one's rate, which
    // bounds both from above (StableDt.cpp).
    double pieceBeta(std::size_t i) const;
    // The piece's smallest-step elements against its median one (StepReport.cpp);
    // computed once per piece, when first asked.
    const PieceStepReport& pieceStepReport(std::size_t piece) const;
    // One clause naming what in the element step limit() points to: the
    // piece, its elements, how many lie near the limit, their quality and the
    // median element's step (empty when no piece sets it).
    std::string describeElementLimit(const StableDt& s) const;
    // Each element's id in the piece's own numbering (the mesh handed to
    // addPiece, before the solver's reordering): ids[local tet].  Default:
    // the solver's local index.
    void setTetIds(int piece, const std::vector<int32_t>& ids);
    int32_t tetId(int32_t globalTet) const {
        return globalTet < static_cast<int32_t>(tetIds_.size()) && tetIds_[globalTet] >= 0
                   ? tetIds_[globalTet] : globalTet - pieces[tetPiece[globalTet]].tetBegin;
    }
    // The same limit on the current shape: stretched elements of a Saint-
    // Venant-Kirchhoff material stiffen beyond the reference step.  Throws
    // StabilityError naming the element, its stretch and the current limit
    // when dt exceeds it (doc/hard_cases.md).  Cheap: exact eigenvalues only
    // for elements whose estimate comes near the limit.
    void checkCurrentDt(double dt) const;
    // Throws StabilityError when a position or velocity became NaN/infinite.
    void checkFinite() const;
    // Refuses a blocked value outside the bit mask 0..7 (InputError naming the node).
    void checkBlockedBits() const;
    // Inverted elements (volume ratio J = det F <= 0) of the awake pieces:
    // how many, and the first one (lowest piece, then element).  One pass of
    // 3x3 determinants: cheap enough for every check period.
    InversionCount countInverted() const;
    // countInverted, and throws StabilityError naming the piece, element,
    // volume ratio and the fix when an inverted element's law cannot push it
    // back (Saint-Venant-Kirchhoff); returns the count otherwise.
    InversionCount checkInverted() const;
    // Throws StabilityError when a surface node of one piece lies inside
    // another deeper than their contact reach r_a + r_b: no contact sees it
    // and the pieces interpenetrate for good (contacts too soft for the load,
    // PieceStartOverlap.cpp).  Reads every node: gatherAll() first under MPI.
    // Collective under MPI: every rank raises the lowest failing rank's error.
    void checkDeepOverlap();
    // A coupled YADE sphere whose centre lies inside a piece deeper than the
    // contact's reach (placed there, or sunk in through a contact too soft
    // for its load) is out of every contact's sight: StabilityError naming
    // it and the fixes.  Reads every node: gatherAll() first under MPI.
    // Collective under MPI.
    void checkSpheresInside() const;
    // Box and Facet edges that cross a piece's surface triangles: an obstacle
    // edge narrower than the node spacing passed between the nodes
    // (ObstacleEdges.cpp).  Reads every node: gatherAll() first under MPI.
    ObstacleEdgeCrossing obstacleEdgeCrossing() const;
    // The checks due at this step, in one call, scheduled here: every
    // checkPeriod steps (iter a multiple of it; 0: never) inverted elements
    // (checkInverted), dt against the current shape (checkCurrentDt, when
    // checkDt), finite state, deep piece overlap, YADE spheres inside pieces,
    // obstacle edges through surfaces, in that order (each names what the
    // one after it would misname).  Under MPI every rank first learns every
    // node (gatherAll): before the checks, and every gatherPeriod steps.
    // Throws what the checks throw (PeriodicChecks.cpp).
    PeriodicChecks periodicChecks(long checkPeriod, long gatherPeriod, double dt, bool checkDt);
    // A number that changes whenever something the stable step depends on
    // has changed since it was last asked: a setting (any of Settings.hpp's,
    // compared member by member), a piece or material added, the obstacles
    // or the YADE spheres set.  A check of dt cached under it (QdemEngine)
    // is redone exactly when its answer could differ (StableStepVersion.cpp).
    long stableStepVersion() const;
    // Pieces that started pressed into an obstacle by more than a quarter of their
    // node radius (ObstaclePhase::takeStartWarnings), handed over once.
    // And pieces placed pressed into each other (PieceContactPhase::takeStartWarnings).
    std::vector<std::string> takeStartWarnings();

    // ---- restarts (Checkpoint.cpp) ---------------------------------------
    // The dynamic state (positions, velocities, contact histories, sleeping
    // pieces, clocks, energy sums); loadState needs the same scene built
    // first and throws InputError naming the mismatch otherwise.
    WorldState saveState() const;
    void loadState(const WorldState& s);

    // ---- MPI (pkg/parallel, doc/parallel.md) --------------------------------
    // Splits the world across the communicator's ranks from the next step on
    // (nullptr or a 1-rank communicator: back to one process).  Every rank
    // must have built the same scene; the split is made at the next step, and
    // again after pieces are added.
    void setCommunicator(std::shared_ptr<Communicator> comm);
    Domain* domain() { return domain_.get(); }
    const Domain* domain() const { return domain_.get(); }
    PartitionOptions partitionOptions;
    // Every rank learns every node's position and velocity (under MPI a rank
    // keeps only its own nodes and ghosts current); a no-op on one process.
    // Collective: every rank must call it.
    void gatherAll();
    // Under MPI: splits the world again along the Hilbert curve from the
    // current positions and contact work, moving every node's state and
    // contact history to its new owner (collective; the step does it when
    // the load drifts past settings.rebalanceThreshold).  No-op on one process.
    void rebalance();
    // gatherAll plus every contact history row: after it every rank holds the
    // whole state, as one process would (saveState needs it under MPI).
    // Collective; a no-op on one process.
    void gatherState();
    // Under MPI, at the end of a script (qdem's exit hook): collective, so a
    // rank still stepping or saving there is told so, as is this one
    // (Domain::agreeOnCall).  A no-op on one process.
    void agreeOnScriptEnd() const;
    // Every node's position, velocity and force is current on this rank
    // (always on one process; under MPI right after gatherAll()).
    bool stateCurrent() const;
    // The energies of the whole world: under MPI the sum over ranks (in rank
    // order) made at the end of each step; `energy` is then this rank's share.
    const Energy& energyTotal() const { return domain_ ? energyTotal_ : energy; }
    void resetEnergy() { energy = energyTotal_ = Energy(); }
    // The lowest failing rank's error on every rank ("" if none failed); on
    // one process, the error itself.  Collective under MPI.
    std::string agreeOnError(const std::string& error) const;

    // ---- output -----------------------------------------------------------
    // Cauchy stress per tet (xx yy zz yz xz xy), elastic plus viscous.
    void computeStress(double* out) const;

    // ---- data (struct of arrays; 3 doubles per node for vectors) ----------
    Column<double> pos, vel, refPos, force, extForce, mass;
    Column<uint8_t> blocked;  // bit d set: DOF d keeps its velocity (prescribed)
    Column<int32_t> nodePiece;
    Column<int32_t> tetNodes, tetPiece;
    Column<double> tetB, tetVol0;   // inverse reference edge matrix (row-major), volume
    // Mass added to each element by selective mass scaling [kg] (0 for most):
    // its nodes carry (rho V + added) / 4 from it, the stable step sees it.
    Column<double> tetAddedMass;
    // Material index of each element (its piece's material unless the piece
    // was added with tetMaterial): its law, Lame constants, viscosity and
    // density.  Set-up data, like tetB: every rank holds all of it.
    Column<int32_t> tetMaterial;
    Column<int32_t> surfNodes;      // global ids of the surface nodes of all pieces
    // Contact weight of each surface node (same index as surfNodes): its share
    // of the piece's surface area over the mean share, A_i / mean(A) with A_i
    // a third of the reference areas of the surface triangles around it.
    // Contact stiffness kn, kt on a node is scaled by w_i (dashpots follow
    // from the scaled k), so a uniform pressure gives a reaction centred on
    // the area centre whatever the mesh: doc/contacts.md, "Area weights".
    Column<double> surfWeight;
    std::vector<PieceInfo> pieces;
    std::vector<Material> materials;
    std::vector<Obstacle> obstacles;
    SphereSet spheres;  // YADE spheres near pieces: states in, forceTorque out

    // ---- settings (Settings.hpp: each declared once) -------------------------
    Settings settings;
    Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // set through setGravity when pieces may sleep
    void setGravity(const Eigen::Vector3d& g);            // wakes sleeping pieces when it changes
    double time = 0;
    long iter = 0;
    Energy energy;

    // ---- sleeping pieces (doc/sleeping.md) ---------------------------------
    // A piece whose nodes have all been slower than sleepVelocity [m/s] for
    // sleepTime [s], and whose neighbour pieces are asleep or as slow, is put
    // to sleep: its velocities are zeroed (energy.sleep books the kinetic
    // energy removed) and it is left out of the step - no element forces, no
    // integration, no contacts with the floor or other sleeping pieces; what
    // it pushed on obstacles stays in their reactions.  It wakes when a
    // neighbour piece moves faster than sleepVelocity, an obstacle near it
    // moves, a YADE sphere comes near, or wake()/wakeAll() is called (the
    // Python Piece does so when its arrays are handed out for writing).
    // settings.sleepVelocity 0 (the default) turns sleeping off.
    bool asleep(std::size_t piece) const { return awake_.asleep(piece); }
    long nAsleep() const { return awake_.nAsleep(); }
    long sleepCount() const;  // pieces put to sleep so far (diagnostics)
    long wakeCount() const;   // and woken
    void wake(std::size_t piece);
    void wakeAll();
    // A piece that is not dynamic (YADE's Body.dynamic) is put to sleep where
    // it is and stays so: nothing wakes it until it is made dynamic again.
    // Awake pieces still touch it as a fixed body; its push on obstacles
    // stays what it was.  Works with sleeping off too.
    bool dynamic(std::size_t piece) const { return awake_.dynamic(piece); }
    void setDynamic(std::size_t piece, bool dynamic);
    // ---- adaptive rigidity (settings.rigidify; doc/formulation.md) ----------
    // A piece slow to deform moves as a rigid body in its current shape until
    // the load on it changes (RigidBodies.hpp).  Serial only (refused under MPI).
    bool rigid(std::size_t piece) const { return awake_.rigid(piece); }
    long nRigid() const { return awake_.nRigid(); }
    long rigidSwitches() const;  // switches rigid <-> deformable so far
    double strainRateEstimate(std::size_t piece) const;  // the last strain-rate estimate of a deformable piece [1/s]
    double rigidLoadChange(std::size_t piece) const;  // a rigid piece's load change, over rigidWakeLoad's scale
    double rigidLoadStrain(std::size_t piece) const;  // the strain that change would make (rigidWakeStrain's)
    // The awake set (AwakeSet.hpp: written by the sleep phase, read by the others).
    const AwakeSet& awakeSet() const { return awake_; }

    std::size_t nNodes() const { return mass.size(); }
    std::size_t nTets() const { return tetVol0.size(); }

    // What the phases measured in the last step (Phase::report): wall times
    // [s] by name (obstacles, broadPhase, pointPolygon, edgeEdge, spheres,
    // elements, integrate, sleep) and counters (contacts: wall,
    // pointPolygon, edgeEdge, sphere; interiorFaceTests, interiorFaceNear).
    PhaseReport report() const;
    long verletRebuilds() const;
    long verletWindowSteps() const;
    bool verletWindowOpen() const;
    // The piece-contact lists and histories (diagnostics, tests: PieceContactState.hpp).
    const PieceContactState& pieceContactState() const;
    const SurfaceIndex& surfaceIndex() const { return surf_; }
    // Box (lo, hi) of each piece's surface nodes now, grown by its particle
    // radius: 6 per piece.  Under MPI the whole pieces' (a reduction of the
    // ranks' owned nodes, made once per step: collective on its first call
    // in a step), so every rank's copy of YADE places its proxies alike.
    const std::vector<double>& pieceBoxes();
    // Point-polygon contacts of the last step: kPP slots per surface node
    // holding 8 * (triangle within its piece) + feature (-1 = empty) and that piece; for diagnostics.
    const Column<int32_t>& pointPolygonKeys() const;
    const Column<int32_t>& pointPolygonKeyPieces() const;
    // Largest overlap of a piece-piece contact in the last step [m].
    double maxPieceOverlap() const;
    // Deepest piece-piece contact of the last step: depth behind the other
    // surface over the reach (the run stops above 1).
    double maxPieceDepthRatio() const;

    World();
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;

private:
    // stableStepVersion(): obstacles and spheres set so far, and what the
    // version was last computed from.
    long inputSets_ = 0;
    mutable long stableStepVersion_ = 0;
    mutable long seenInputSets_ = -1;
    mutable std::size_t seenPieces_ = 0, seenMaterials_ = 0;
    mutable Settings seenSettings_{};
    // Derived per-step data the phases share (each phase declares which it
    // reads or writes: its Data).
    // Which pieces sleep, and the awake pieces' tets, nodes and surface
    // nodes: written by the sleep phase, read by the others.
    AwakeSet awake_;
    // The surfaces of all pieces in global ids, with their adjacency.
    SurfaceIndex surf_;
    // Where each piece can touch anything this step.
    PieceBounds bounds_{{.pos = pos, .surfNodes = surfNodes, .nodePiece = nodePiece, .pieces = pieces,
                         .materials = materials, .settings = settings, .sleeping = awake_, .spheres = spheres,
                         .domain = {domain_}}};
    // Per node, from obstacles, piece contacts and spheres.
    ContactForces contactForces_{pieces, surfNodes, awake_};
    // Energy states per piece (elastic, contact with obstacles, contact with
    // pieces: 3 each), kept for sleeping pieces, summed per thread when tracked.
    std::vector<double> pieceEnergy_;
    std::vector<std::vector<double>> threadPieceEnergy_;
    // Per piece, its stiffest element's omega^2 and explicit viscous rate,
    // refreshed before each step's piece contacts (refreshElementModes).
    std::vector<double> pieceElementW2_, pieceElementRate_;
    // Under MPI: this rank's share of the world and its exchanges.
    std::unique_ptr<Domain> domain_;

    // The phases of World::step (Phases.hpp), each built from the data it
    // declares.  Domain, which moves every row of the world between ranks,
    // is the one friend besides.
    friend class Domain;
    friend struct WorldPhases;
    std::unique_ptr<WorldPhases> phases_;
    const std::array<Phase*, 6>& phases();
    std::array<const Phase*, 6> phases() const;
    // addPiece's steps: the checks that refuse a mesh before anything
    // changes; its nodes and tets appended; the mass added to its elements
    // (selective mass scaling); its surface, with the contact weights.
    void checkNewPiece(const TetMesh& mesh, int material, const std::vector<double>& tetAddedMass,
                       const std::vector<int32_t>& tetMaterial) const;
    void appendNodesAndTets(const TetMesh& mesh, const std::vector<int32_t>& tetMaterial, int pieceId, PieceInfo& p);
    void addElementMass(const TetMesh& mesh, const std::vector<double>& tetAddedMass, const Surface& s,
                        PieceInfo& p);
    void appendSurface(Surface s, PieceInfo& p);

    // The arrays a restart keeps (Checkpoint.cpp): the world's and its phases'.
    StateColumns stateColumns();

    double elementOmegaMax(const PieceInfo& p) const;
    // omegaCache_ for the current pieces (computed when pieces changed).
    void ensureElementOmegas() const;
    // pieceElementW2_, pieceElementRate_ from omegaCache_ and the current
    // viscosity settings: for the piece-contact phase's run-time step.
    void refreshElementModes();
    // The lumped mass one element puts on each of its nodes: (rho V + added) / 4.
    double elementNodeMass(int32_t tet, const Material& m) const {
        return (m.density * tetVol0[tet] + tetAddedMass[tet]) / 4.0;
    }
    // The material of one element (tetMaterial).
    const Material& tetMat(int32_t tet) const { return materials[tetMaterial[tet]]; }
    void beginPieceEnergy();
    void finishPieceEnergy();
    void contactMode(std::size_t piece, double& wc, double& xic) const;
    bool tangentialSprings() const;
    // Stable step of a dynamic obstacle on the node springs that can act on
    // it at once (infinite for a fixed one): StableDt.cpp.
    double dynamicObstacleLimit(const Obstacle& o) const;

    Energy energyTotal_;
    long gatheredIter_ = -1;  // the step gatherAll() last made every node current at
    long rowsGatheredIter_ = -1;  // and gatherState() every history row
    void prepareDomain(double dt);
    // Throws InputError under MPI unless gatherAll() made every node current this step.
    void requireGathered(const char* what) const;
    std::vector<double> boxes_;  // pieceBoxes(), made at step boxesIter_
    long boxesIter_ = -1;
    mutable std::vector<double> omegaCache_;  // per piece, element omega_max
    mutable std::vector<double> pieceRateMax_;  // per piece, largest beta_e omega_e^2 over its elements
    // The two smallest mean areas per surface node over the pieces, and the
    // piece with the smallest (contactMode: the finest other piece), for
    // shareCacheN_ pieces: once per piece added, not once per piece per call.
    mutable std::size_t shareCacheN_ = 0;
    mutable double shareMin1_ = 0, shareMin2_ = 0;
    mutable std::size_t shareArgMin_ = 0;
    mutable std::vector<PieceStepReport> stepReports_;  // per piece (pieceStepReport)
    mutable std::vector<char> stepReportDone_;
    std::vector<int32_t> tetIds_;  // per tet, its id in the piece's own numbering (-1: the local index)
    mutable std::vector<double> omega2Tet_;   // per tet, reference omega^2 (exact, or an upper bound below the max)
};

}  // namespace qdem
