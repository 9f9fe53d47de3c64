// Set-up of the world: materials, pieces, obstacles.
#include "World.hpp"
#include "Phases.hpp"

#include <algorithm>
#include <cmath>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/Tetra.hpp"
#include "../mesh/Components.hpp"
#include "../parallel/Domain.hpp"

namespace qdem {

int World::addMaterial(const Material& m) {
    m.validate();
    materials.push_back(m);
    omegaCache_.clear();
    return static_cast<int>(materials.size()) - 1;
}

void World::checkNewPiece(const TetMesh& mesh, int material, const std::vector<double>& tetAddedMass_,
                          const std::vector<int32_t>& tetMaterial_) const {
    if (material < 0 || material >= static_cast<int>(materials.size()))
        throw InputError(cat("addPiece: unknown material index ", material));
    checkMesh(mesh);
    if (!tetMaterial_.empty()) {
        if (tetMaterial_.size() != mesh.nTets())
            throw InputError(cat("addPiece: tetMaterial has ", tetMaterial_.size(), " values for ", mesh.nTets(),
                                 " tetrahedra (one material index per tetrahedron, or none)"));
        for (std::size_t e = 0; e < tetMaterial_.size(); ++e) {
            if (tetMaterial_[e] < 0 || tetMaterial_[e] >= static_cast<int32_t>(materials.size()))
                throw InputError(cat("addPiece: tetMaterial[", e, "] = ", tetMaterial_[e], " is no material index (0 to ",
                                     materials.size() - 1, ")"));
            // One radius per surface: the nodes' contact reach is the piece's.
            if (materials[tetMaterial_[e]].radius != materials[material].radius)
                throw InputError(cat("addPiece: the materials of a bonded piece must share one contact radius; element ",
                                     e, " has radius ", materials[tetMaterial_[e]].radius, " m, the piece's contact "
                                     "material ", materials[material].radius, " m: give every region's QdemMat the "
                                     "same radius"));
        }
    }
    if (!tetAddedMass_.empty()) {
        if (tetAddedMass_.size() != mesh.nTets())
            throw InputError(cat("addPiece: tetAddedMass has ", tetAddedMass_.size(), " values for ", mesh.nTets(),
                                 " tetrahedra (one per tetrahedron, or none)"));
        for (std::size_t e = 0; e < tetAddedMass_.size(); ++e)
            if (!(tetAddedMass_[e] >= 0) || !std::isfinite(tetAddedMass_[e]))
                throw InputError(cat("addPiece: tetAddedMass[", e, "] = ", tetAddedMass_[e],
                                     ": added mass must be finite and >= 0 kg"));
    }
    checkOnePart(mesh);  // parts of one piece would pass through each other
    // Every node needs mass: checked before anything changes, so that a
    // refused mesh leaves the world as it was (no hidden nodes).
    {
        std::vector<double> m(mesh.nNodes(), 0.0);
        for (std::size_t e = 0; e < mesh.nTets(); ++e) {
            const int32_t* c = &mesh.tets[4 * e];
            const double V = edgeMatrix(&mesh.nodes[3 * c[0]], &mesh.nodes[3 * c[1]], &mesh.nodes[3 * c[2]],
                                        &mesh.nodes[3 * c[3]])
                                 .determinant() /
                             6.0;
            const Material& mat = materials[tetMaterial_.empty() ? material : tetMaterial_[e]];
            for (int k = 0; k < 4; ++k) m[c[k]] += mat.density * V / 4.0;
        }
        std::vector<char> used(mesh.nNodes(), 0);
        for (const int32_t v : mesh.tets) used[v] = 1;
        for (std::size_t i = 0; i < m.size(); ++i) {
            if (!used[i])
                throw InputError(cat("addPiece: node ", i, " belongs to no tetrahedron (zero mass); remove unused nodes"));
            if (!(m[i] > 0) || !std::isfinite(m[i]))
                throw InputError(cat("addPiece: node ", i, " gets mass ", m[i], " (density ", materials[material].density,
                                     " times its tetrahedra's volume): coordinates or density out of floating "
                                     "point range; give the mesh in metres and the density in kg/m^3"));
        }
    }
}

int World::addPiece(const TetMesh& mesh, int material, const std::vector<double>& tetAddedMass_,
                    const std::vector<int32_t>& tetMaterial_) {
    checkNewPiece(mesh, material, tetAddedMass_, tetMaterial_);
    PieceInfo p;
    p.material = material;
    std::vector<int32_t> tm = tetMaterial_.empty() ? std::vector<int32_t>(mesh.nTets(), material) : tetMaterial_;
    {
        std::vector<int32_t> distinct(tm);
        std::sort(distinct.begin(), distinct.end());
        distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
        p.materialCount = static_cast<int32_t>(distinct.size());
        p.maxViscosity = materials[material].viscosity;
        if (!tetMaterial_.empty()) {
            p.maxViscosity = 0;
            for (const int32_t k : distinct) p.maxViscosity = std::max(p.maxViscosity, materials[k].viscosity);
        }
    }
    const auto n0 = static_cast<int32_t>(nNodes());
    const auto t0 = static_cast<int32_t>(nTets());
    const auto nn = static_cast<int32_t>(mesh.nNodes());
    const auto nt = static_cast<int32_t>(mesh.nTets());
    p.nodeBegin = n0;
    p.nodeEnd = n0 + nn;
    p.tetBegin = t0;
    p.tetEnd = t0 + nt;
    const int pieceId = static_cast<int>(pieces.size());

    // Surface first: it throws on a non-manifold mesh before anything changes.
    Surface s = extractSurface(mesh);
    appendNodesAndTets(mesh, tm, pieceId, p);
    if (!tetAddedMass_.empty()) addElementMass(mesh, tetAddedMass_, s, p);
    appendSurface(std::move(s), p);

    pieces.push_back(std::move(p));
    surf_.build(pieces, tetNodes.data(), nTets(), surfNodes.data(), surfNodes.size(), nNodes());
    surf_.classifyEdges(refPos.data(), settings.edgeFeatureAngle);
    omegaCache_.clear();
    if (domain_) domain_->invalidate();  // split again at the next step
    for (Phase* ph : phases()) ph->piecesAdded();
    pieceEnergy_.resize(3 * pieces.size(), 0.0);
    return pieceId;
}

// The piece's nodes and tets at the end of the world's arrays: reference
// positions, inverse edge matrices, volumes and the lumped masses rho V / 4.
void World::appendNodesAndTets(const TetMesh& mesh, const std::vector<int32_t>& tm, int pieceId, PieceInfo& p) {
    const int32_t n0 = p.nodeBegin, t0 = p.tetBegin;
    const int32_t nn = p.nodeEnd - p.nodeBegin, nt = p.tetEnd - p.tetBegin;
    const std::size_t N = n0 + nn, T = t0 + nt;
    pos.resize(3 * N);
    vel.resize(3 * N, 0.0);
    refPos.resize(3 * N);
    force.resize(3 * N, 0.0);
    extForce.resize(3 * N, 0.0);
    contactForces_.force.resize(3 * N, 0.0);
    mass.resize(N, 0.0);
    blocked.resize(N, 0);
    nodePiece.resize(N, pieceId);
    tetNodes.resize(4 * T);
    tetPiece.resize(T, pieceId);
    tetB.resize(9 * T);
    tetVol0.resize(T);
    tetAddedMass.resize(T, 0.0);
    tetMaterial.resize(T);
    double pieceMass = 0;

    for (int32_t i = 0; i < nn; ++i)
        for (int d = 0; d < 3; ++d) {
            pos[3 * (n0 + i) + d] = mesh.nodes[3 * i + d];
            refPos[3 * (n0 + i) + d] = mesh.nodes[3 * i + d];
        }
    for (int32_t e = 0; e < nt; ++e) {
        const int32_t* c = &mesh.tets[4 * e];
        for (int k = 0; k < 4; ++k) tetNodes[4 * (t0 + e) + k] = n0 + c[k];
        const Mat3 Dm = edgeMatrix(&mesh.nodes[3 * c[0]], &mesh.nodes[3 * c[1]], &mesh.nodes[3 * c[2]],
                                   &mesh.nodes[3 * c[3]]);
        const double V = Dm.determinant() / 6.0;
        const Mat3 B = Dm.inverse();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) tetB[9 * (t0 + e) + 3 * i + j] = B(i, j);
        tetVol0[t0 + e] = V;
        tetMaterial[t0 + e] = tm[e];
        const Material& mat = materials[tm[e]];
        const double m4 = mat.density * V / 4.0;  // lumped mass: a quarter to each node
        for (int k = 0; k < 4; ++k) mass[n0 + c[k]] += m4;
        p.volume += V;
        pieceMass += mat.density * V;
    }
    // (One material: rho times the summed volume, as the mass always was.)
    p.mass = p.materialCount == 1 ? materials[tm[0]].density * p.volume : pieceMass;
}

// Selective mass scaling: each element's added mass lumped as its own,
// a quarter to each node, after the physical masses (kept apart to
// report the largest share at a node).
void World::addElementMass(const TetMesh& mesh, const std::vector<double>& tetAddedMass_, const Surface& s,
                           PieceInfo& p) {
    const int32_t n0 = p.nodeBegin, t0 = p.tetBegin;
    const int32_t nn = p.nodeEnd - p.nodeBegin, nt = p.tetEnd - p.tetBegin;
    std::vector<double> added(nn, 0.0);
    for (int32_t e = 0; e < nt; ++e) {
        const double a = tetAddedMass_[e];
        tetAddedMass[t0 + e] = a;
        if (a > 0) ++p.addedElements;
        for (int k = 0; k < 4; ++k) added[mesh.tets[4 * e + k]] += a / 4.0;
        p.addedMass += a;
    }
    for (int32_t i = 0; i < nn; ++i) {
        if (!(added[i] > 0)) continue;
        const double share = added[i] / mass[n0 + i];
        if (share > p.addedMaxNodeShare) p.addedMaxNodeShare = share, p.addedMaxNode = n0 + i;
        mass[n0 + i] += added[i];
    }
    for (const int32_t v : s.nodes) p.addedSurfaceMass += added[v];
    p.mass += p.addedMass;
}

// The piece's surface in global ids, its nodes' contact weights (area
// shares over the mean) and the extremes the stable step reads.
void World::appendSurface(Surface s, PieceInfo& p) {
    const int32_t n0 = p.nodeBegin, t0 = p.tetBegin;
    const int32_t nn = p.nodeEnd - p.nodeBegin;
    // Surface in global ids.
    for (auto& v : s.triangles) v += n0;
    for (auto& v : s.edges) v += n0;
    for (auto& v : s.nodes) v += n0;
    for (auto& v : s.triTet) v += t0;
    for (auto& v : s.tets) v += t0;
    p.surfBegin = static_cast<int32_t>(surfNodes.size());
    surfNodes.resize(surfNodes.size() + s.nodes.size());
    surfWeight.resize(surfNodes.size(), 1.0);
    // Area share of each surface node (a third of each reference triangle's
    // area), normalised by the mean: surfWeight (World.hpp).
    std::vector<double> share(nn, 0.0);
    for (std::size_t t = 0; t < s.nTriangles(); ++t) {
        const int32_t* v = &s.triangles[3 * t];
        auto x = [&](int32_t g) { return Eigen::Vector3d(refPos[3 * g], refPos[3 * g + 1], refPos[3 * g + 2]); };
        const Eigen::Vector3d a = x(v[0]), b = x(v[1]), c = x(v[2]);
        const double third = (b - a).cross(c - a).norm() / 6.0;
        for (int k = 0; k < 3; ++k) share[v[k] - n0] += third;
    }
    double shareSum = 0;
    for (const int32_t v : s.nodes) shareSum += share[v - n0];
    const double meanShare = shareSum / static_cast<double>(s.nodes.size());
    double mmin = std::numeric_limits<double>::infinity(), mmax = 0, mwmin = mmin, mwmax = 0, wmin = mmin;
    for (std::size_t i = 0; i < s.nodes.size(); ++i) {
        surfNodes[p.surfBegin + i] = s.nodes[i];
        mmin = std::min(mmin, mass[s.nodes[i]]);
        mmax = std::max(mmax, mass[s.nodes[i]]);
        // > 0: every surface node is a corner of a surface face of a checked
        // (non-flat) tetrahedron.
        const double w = share[s.nodes[i] - n0] / meanShare;
        surfWeight[p.surfBegin + i] = w;
        mwmin = std::min(mwmin, mass[s.nodes[i]] / w);
        mwmax = std::max(mwmax, mass[s.nodes[i]] / w);
        wmin = std::min(wmin, w);
    }
    p.surfEnd = static_cast<int32_t>(surfNodes.size());
    p.minSurfaceNodeMass = mmin;
    p.maxSurfaceNodeMass = mmax;
    p.minSurfaceMassPerWeight = mwmin;
    p.maxSurfaceMassPerWeight = mwmax;
    p.minSurfaceWeight = wmin;
    p.meanSurfaceShare = meanShare;
    p.surface = std::move(s);
}

void World::setObstacles(const std::vector<Obstacle>& obs) {
    for (const auto& o : obs) {
        if (o.kind == ObstacleKind::Wall && (o.axis < 0 || o.axis > 2))
            throw InputError(cat("obstacle ", o.bodyId, ": wall axis must be 0, 1 or 2, got ", o.axis));
        if (o.kind == ObstacleKind::Box && !(o.halfExtents.minCoeff() >= 0))
            throw InputError(cat("obstacle ", o.bodyId, ": box extents must be >= 0"));
        if (!(o.invMass >= 0) || !(o.invInertia >= 0) || !(o.armOffset >= 0) || !std::isfinite(o.armOffset))
            throw InputError(cat("obstacle ", o.bodyId, ": invMass, invInertia must be >= 0 (infinite: a free DOF ",
                                 "of zero mass), armOffset finite and >= 0; got ", o.invMass, ", ", o.invInertia,
                                 ", ", o.armOffset));
    }
    const std::vector<double> sig = obstacleSignature(obs);
    const bool same = phases_->sleep.obstaclesSet(sig, obstacleSignature(obstacles));  // false: all woken
    obstacles = obs;
    for (auto& o : obstacles) o.updateDerived();
    if (!same) phases_->obstacle.obstaclesChanged();
    omegaCache_.clear();
    ++inputSets_;
}

void World::setObstacleState(int i, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
                             const Eigen::Vector3d& v, const Eigen::Vector3d& w, const Eigen::Vector3d& c) {
    if (i < 0 || i >= static_cast<int>(obstacles.size()))
        throw InputError(cat("setObstacleState: no obstacle ", i));
    Obstacle& o = obstacles[i];
    o.pos = p;
    o.ori = q;
    o.vel = v;
    o.angVel = w;
    o.spinCentre = c;
    o.updateDerived();
}

void World::requireGathered(const char* what) const {
    if (!stateCurrent())
        throw InputError(cat(what, " under MPI reads every node: call gatherAll() on every rank first (QdemEngine does "
                             "so before its checks and output)"));
}

void World::checkFinite() const {
    requireGathered("checkFinite");
    const std::size_t n = 3 * nNodes();
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(pos[i]) || !std::isfinite(vel[i]))
            throw StabilityError(cat("QDEM state is not finite at node ", i / 3, " (piece ", nodePiece[i / 3],
                                     ") after step ", iter, ": the integration blew up"));
}

const std::vector<double>& World::pieceBoxes() {
    const bool split = domain_ && domain_->built();
    if (split && boxesIter_ == iter && boxes_.size() == 6 * pieces.size()) return boxes_;
    const std::size_t np = pieces.size();
    boxes_.assign(6 * np, 0.0);
    for (std::size_t p = 0; p < np; ++p) {
        const PieceInfo& pc = pieces[p];
        const double r = materials[pc.material].radius;
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
        for (int32_t s = pc.surfBegin; s < pc.surfEnd; ++s) {
            const int32_t n = surfNodes[s];
            if (split && !domain_->owns(n)) continue;  // every node counted by its owner, current there
            for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], pos[3 * n + d]), hi[d] = std::max(hi[d], pos[3 * n + d]);
        }
        for (int d = 0; d < 3; ++d) boxes_[6 * p + d] = lo[d] - r, boxes_[6 * p + 3 + d] = -(hi[d] + r);
    }
    if (split) domain_->comm().allreduceMin(boxes_.data(), static_cast<int>(6 * np));  // min of lo and of -hi
    for (std::size_t p = 0; p < np; ++p)
        for (int d = 0; d < 3; ++d) boxes_[6 * p + 3 + d] = -boxes_[6 * p + 3 + d];
    boxesIter_ = split ? iter : -1;
    return boxes_;
}

void World::setGravity(const Eigen::Vector3d& g) {
    const Eigen::Vector3d old = gravity;
    gravity = g;
    phases_->sleep.gravitySet(old, g);
}

void World::setDynamic(std::size_t p, bool dynamic) {
    if (p >= pieces.size()) throw InputError(cat("setDynamic: no piece ", p));
    phases_->sleep.setDynamic(p, dynamic);
}

}  // namespace qdem

// ---------------------------------------------------------------------------
// MPI (pkg/parallel/Domain.hpp)

namespace qdem {

void World::setCommunicator(std::shared_ptr<Communicator> comm) {
    boxesIter_ = -1;
    if (comm && comm->size() > 1) domain_ = std::make_unique<Domain>(*this, std::move(comm));
    else domain_.reset();
    phases_->sleep.awakeSetChanged();
}

// Before each step under MPI: every rank's YADE copy checked alike (walls,
// spheres), the world split at the first step (and again after pieces were
// added), the contact halo widened for the spheres listed.  Each check is
// collective and decided alike everywhere, so no rank waits for another.
void World::prepareDomain(double dt) {
    if (domain_->built()) {
        domain_->checkYadeAlike(dt);    // before any message sized by them
        domain_->ensureSphereHalo();  // spheres listed since, or larger ones: a wider contact halo now
        return;
    }
    const bool first = !domain_->everBuilt();
    if (!first) {
        // Split again (pieces were added): every rank must hold the whole
        // state first, as the split is made by each rank from its own copy.
        domain_->gatherAll();
        domain_->gatherRows();
    }
    domain_->checkYadeAlike(dt);
    domain_->build(partitionOptions);
    phases_->sleep.awakeSetChanged();
    energyTotal_ = energy;
    // Until now every rank summed the whole world's energies: from here on
    // each sums its share, so what was summed counts once (on rank 0).
    if (first && domain_->rank() != 0) energy = Energy{};
}

void World::rebalance() {
    if (!domain_ || !domain_->built()) return;
    domain_->agreeOnCall(Domain::Call::Rebalance);
    domain_->rebalance(partitionOptions);
    phases_->sleep.awakeSetChanged();
    gatheredIter_ = iter;  // rebalance gathered every node
}

void World::gatherState() {
    if (domain_ && domain_->built()) {
        domain_->agreeOnCall(Domain::Call::GatherState);
        domain_->gatherAll();
        domain_->gatherRows();
    }
    gatheredIter_ = rowsGatheredIter_ = iter;
}

void World::gatherAll() {
    if (domain_ && domain_->built()) {
        domain_->agreeOnCall(Domain::Call::GatherAll);
        domain_->gatherAll();
    }
    gatheredIter_ = iter;
}

void World::agreeOnScriptEnd() const {
    if (domain_) domain_->agreeOnCall(Domain::Call::ScriptEnd);
}

std::string World::agreeOnError(const std::string& error) const {
    if (!domain_) return error;
    const std::string m = domain_->agree(error.empty() ? error : "S0" + error);
    return m.empty() ? m : m.substr(1);
}

}  // namespace qdem

namespace qdem {

// (Before the first split every rank holds the whole set-up.)
bool World::stateCurrent() const { return !domain_ || !domain_->built() || gatheredIter_ == iter; }

}  // namespace qdem
