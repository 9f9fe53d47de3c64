// The QDEM world: pieces, obstacles, stepping, energies, NumPy views.
#include <cmath>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "Arrays.hpp"
#include "core/Errors.hpp"
#include "core/Format.hpp"
#include "phases/PieceContactState.hpp"
#include "phases/PointPolygonKind.hpp"
#include "world/World.hpp"

namespace py = pybind11;
using namespace qdem;
using qdem::py_::columnView;
using qdem::py_::flatten;

void bindSettings(py::module_& m, py::class_<World>& world);
void bindParallel(py::module_& m, py::class_<World>& world);
void bindMaterial(py::module_& m, py::class_<World>& world);

namespace {

using Nodes = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Tets = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;

py::dict energyDict(const Energy& e) {
    py::dict d;
    d["kinetic"] = e.kinetic;
    d["elastic"] = e.elastic;
    d["gravity"] = e.gravity;
    d["viscous"] = e.viscous;
    d["contactElastic"] = e.contactElastic;
    d["contactDamping"] = e.contactDamping;
    d["friction"] = e.friction;
    d["boundaryWork"] = e.boundaryWork;
    d["localDamping"] = e.localDamping;
    d["sleep"] = e.sleep;
    d["rigid"] = e.rigid;
    d["total"] = e.total();
    return d;
}


// (begin, end) ranges of piece i in the global arrays.
const PieceInfo& piece(const World& w, int i) {
    if (i < 0 || i >= static_cast<int>(w.pieces.size())) throw InputError("no piece " + std::to_string(i));
    return w.pieces[i];
}

template <class T>
py::array_t<T> copyOut(const std::vector<T>& v, py::ssize_t cols) {
    py::array_t<T> a({static_cast<py::ssize_t>(v.size()) / cols, cols});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
}

}  // namespace

void bindWorld(py::module_& m) {
    py::class_<Obstacle>(m, "Obstacle", "A rigid YADE body seen by QDEM nodes (wall, box or facet).")
        .def(py::init<>())
        .def_property(
            "kind", [](const Obstacle& o) { return static_cast<int>(o.kind); },
            [](Obstacle& o, int k) {
                if (k < 0 || k > 2) throw InputError("Obstacle.kind must be 0 (wall), 1 (box) or 2 (facet)");
                o.kind = static_cast<ObstacleKind>(k);
            })
        .def_readwrite("bodyId", &Obstacle::bodyId)
        .def_readwrite("young", &Obstacle::young)
        .def_readwrite("friction", &Obstacle::friction)
        .def_readwrite("invMass", &Obstacle::invMass)
        .def_readwrite("invInertia", &Obstacle::invInertia)
        .def_readwrite("armOffset", &Obstacle::armOffset)
        .def_readwrite("axis", &Obstacle::axis)
        .def_readwrite("sense", &Obstacle::sense)
        .def_readwrite("halfExtents", &Obstacle::halfExtents)
        .def("setVertices",
             [](Obstacle& o, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
                 o.localVerts[0] = a;
                 o.localVerts[1] = b;
                 o.localVerts[2] = c;
             })
        .def_readonly("reactionForce", &Obstacle::reactionForce)
        .def_readonly("reactionTorque", &Obstacle::reactionTorque);

    py::class_<World> world(m, "World", "All QDEM pieces of a scene and their step pipeline.");
    bindSettings(m, world);
    bindParallel(m, world);
    bindMaterial(m, world);
    world.def(py::init<>())
        .def(
            "addPiece",
            [](World& w, const Nodes& nodes, const Tets& tets, int material, const std::vector<double>& added,
               const std::vector<int32_t>& tetMaterial) {
                TetMesh mesh;
                mesh.nodes = flatten<double>(nodes, 3, "nodes");
                mesh.tets = flatten<int32_t>(tets, 4, "tets");
                return w.addPiece(mesh, material, added, tetMaterial);
            },
            py::arg("nodes"), py::arg("tets"), py::arg("material"), py::arg("tetAddedMass") = std::vector<double>{},
            py::arg("tetMaterial") = std::vector<int32_t>{},
            "Add a piece (world coordinates); tetAddedMass: mass added to each tet [kg] (selective mass "
            "scaling, massScaling), a quarter to each of its nodes; tetMaterial: a material index per tet (a "
            "bonded piece of several materials; material is then its contact material), or none.")
        .def(
            "massScaling",
            [](const World& w, const Nodes& nodes, const Tets& tets, int material, double targetDt) {
                TetMesh mesh;
                mesh.nodes = flatten<double>(nodes, 3, "nodes");
                mesh.tets = flatten<int32_t>(tets, 4, "tets");
                const std::vector<double> a = w.massScaling(mesh, material, targetDt);
                py::array_t<double> out(py::ssize_t(a.size()));
                std::copy(a.begin(), a.end(), out.mutable_data());
                return out;
            },
            py::arg("nodes"), py::arg("tets"), py::arg("material"), py::arg("targetDt"),
            "Per tet, the least mass [kg] to add so that its own stable step (elastic and viscous) reaches "
            "targetDt as stableDt() computes it (0 where it does already).")
        .def(
            "rigidContactLimit",
            [](const World& w, int i) {
                piece(w, i);
                double contact = 0, combined = 0;
                w.rigidContactLimit(static_cast<std::size_t>(i), contact, combined);
                return py::make_tuple(contact, combined);
            },
            py::arg("piece"),
            "(contact, combined): the stable step of piece i's contact springs against a rigid wall, alone and "
            "with its element springs on the same node.")
        .def(
            "pieceMassScaling",
            [](const World& w, int i) {
                const PieceInfo& p = piece(w, i);
                py::dict d;
                d["addedMass"] = p.addedMass;
                d["physicalMass"] = p.mass - p.addedMass;
                d["maxNodeShare"] = p.addedMaxNodeShare;
                d["maxNode"] = p.addedMaxNode < 0 ? -1 : p.addedMaxNode - p.nodeBegin;
                d["surfaceMass"] = p.addedSurfaceMass;
                d["elements"] = p.addedElements;
                return d;
            },
            py::arg("piece"),
            "Selective mass scaling of a piece: addedMass [kg], physicalMass (rho V) [kg], maxNodeShare (largest "
            "added mass at one node over that node's own mass) at maxNode (piece-local, -1: none), surfaceMass "
            "(added on surface nodes) [kg], elements (how many got mass).")
        .def(
            "removeLastMaterial",
            [](World& w) {
                if (w.materials.empty()) throw InputError("removeLastMaterial: the world has no material");
                const int last = static_cast<int>(w.materials.size()) - 1;
                for (const auto& p : w.pieces)
                    if (p.material == last)
                        throw InputError(cat("removeLastMaterial: material ", last, " is used by a piece"));
                w.materials.pop_back();
            },
            "Forget the last material added, when no piece uses it (addPiece undoing a refused piece).")
        .def("setObstacles", &World::setObstacles)
        .def(
            "setObstacleStates",
            [](World& w, const py::array_t<double, py::array::c_style | py::array::forcecast>& s) {
                if (s.ndim() != 2 || (s.shape(1) != 13 && s.shape(1) != 16) ||
                    s.shape(0) != static_cast<py::ssize_t>(w.obstacles.size()))
                    throw InputError("setObstacleStates: expected shape (nObstacles, 13) or (nObstacles, 16)");
                auto r = s.unchecked<2>();
                const int c = s.shape(1) == 16 ? 13 : 0;  // spin centre's columns; 13 columns: pos itself
                for (py::ssize_t i = 0; i < s.shape(0); ++i)
                    w.setObstacleState(static_cast<int>(i), {r(i, 0), r(i, 1), r(i, 2)},
                                       Eigen::Quaterniond(r(i, 3), r(i, 4), r(i, 5), r(i, 6)),
                                       {r(i, 7), r(i, 8), r(i, 9)}, {r(i, 10), r(i, 11), r(i, 12)},
                                       {r(i, c), r(i, c + 1), r(i, c + 2)});
            },
            "Rows: pos(3), quaternion w x y z, vel(3), angVel(3) and optionally the spin centre (3): a clump "
            "member's clump centre, whose velocity vel + angVel x (centre - pos) is (default pos).")
        .def(
            "obstacleReactions",
            [](const World& w) {
                py::array_t<double> a({static_cast<py::ssize_t>(w.obstacles.size()), py::ssize_t(6)});
                auto r = a.mutable_unchecked<2>();
                for (std::size_t i = 0; i < w.obstacles.size(); ++i)
                    for (int d = 0; d < 3; ++d) {
                        r(i, d) = w.obstacles[i].reactionForce[d];
                        r(i, 3 + d) = w.obstacles[i].reactionTorque[d];
                    }
                return a;
            },
            "Force and torque (about the body position) on each obstacle in the last step.")
        .def(
            "step",
            [](World& w, double dt, long n) {
                py::gil_scoped_release nogil;
                for (long i = 0; i < n; ++i) w.step(dt);
            },
            py::arg("dt"), py::arg("n") = 1)
        .def("checkDt", &World::checkDt, py::arg("dt"))
        .def("checkFinite", &World::checkFinite)
        .def("checkSpheresInside", &World::checkSpheresInside,
             "Raise StabilityError if a coupled YADE sphere's centre lies inside a piece deeper than the contact's "
             "reach (QdemEngine calls it every checkPeriod steps).")
        .def("checkDeepOverlap", &World::checkDeepOverlap,
             "Raise StabilityError when a surface node of a piece lies inside another piece deeper than their "
             "contact reach r_a + r_b (the contact cannot see it: the pieces interpenetrate for good).")
        .def(
            "checkInverted",
            [](const World& w) {
                const InversionCount r = w.checkInverted();
                py::dict d;
                d["count"] = r.count;
                d["piece"] = r.piece;
                d["element"] = r.element;
                d["volumeRatio"] = r.volumeRatio;
                return d;
            },
            "Inverted elements (volume ratio <= 0) of the awake pieces: dict of count and the first one's piece, "
            "element and volumeRatio.  Raises StabilityError naming them when their law cannot push them back "
            "(saintVenantKirchhoff).")
        .def(
            "obstacleEdgeCrossing",
            [](const World& w) {
                const ObstacleEdgeCrossing r = w.obstacleEdgeCrossing();
                py::dict d;
                d["count"] = r.count;
                d["obstacle"] = r.obstacle;
                d["bodyId"] = r.bodyId;
                d["piece"] = r.piece;
                d["point"] = py::make_tuple(r.point[0], r.point[1], r.point[2]);
                return d;
            },
            "Box and Facet edges crossing a piece's surface triangles (an edge narrower than the node spacing "
            "passed between the nodes): dict of count and the first one's obstacle index, YADE bodyId, piece "
            "and point.")
        .def("takeStartWarnings", &World::takeStartWarnings,
             "Messages about pieces that started pressed into a YADE obstacle by more than a quarter of their node "
             "radius / 4 (thrown off by their contact springs), each handed over once; QdemEngine warns with them.")
        .def("checkCurrentDt", &World::checkCurrentDt, py::arg("dt"),
             "Raise StabilityError when dt exceeds the stable step of the current (strained) shape.")
        .def("stableDt",
             [](const World& w) {
                 const StableDt s = w.stableDt();
                 py::dict d;
                 d["elastic"] = s.elastic;
                 d["viscous"] = s.viscous;
                 d["contact"] = s.contact;
                 d["combined"] = s.combined;
                 d["combinedExplicit"] = s.combinedExplicit;
                 d["combinedImplicit"] = s.combinedImplicit;
                 d["limitedBy"] = s.limitedBy;
                 d["obstacle"] = s.obstacle;  // the stiffest dynamic YADE obstacle's (inf: none)
                 // The piece-piece contacts as the last step found them (inf: none).
                 d["pieceContact"] = s.pieceContact;
                 d["pieceContactNode"] = s.pieceContactNode;
                 d["pieceContactPiece"] = s.pieceContactPiece;
                 // What in the element step sets it (StableDt, StepReport.hpp).
                 d["piece"] = s.piece;
                 d["elements"] = s.elements;
                 d["elementsNearLimit"] = s.elementsNearLimit;
                 d["worstQuality"] = s.worstQuality;
                 d["medianElastic"] = s.medianElastic;
                 d["medianViscous"] = s.medianViscous;
                 d["medianFactorElastic"] = s.piece >= 0 ? s.medianElastic / s.pieceElastic : 1.0;
                 d["medianFactorViscous"] = s.piece >= 0 ? s.medianViscous / s.pieceViscous : 1.0;
                 d["elementLimit"] = w.describeElementLimit(s);
                 return d;
             })
        .def("pieceStepReport",
             [](const World& w, int piece) {
                 if (piece < 0 || piece >= static_cast<int>(w.pieces.size()))
                     throw InputError(cat("pieceStepReport: no piece ", piece));
                 const PieceStepReport& r = w.pieceStepReport(piece);
                 const PieceInfo& p = w.pieces[piece];
                 std::vector<int32_t> ids;
                 for (int32_t local : r.worst) ids.push_back(w.tetId(p.tetBegin + local));
                 py::dict d;
                 d["omegaMax"] = r.omegaMax;
                 d["omegaMedian"] = r.omegaMedian;
                 d["elements"] = ids;
                 d["elementsNearLimit"] = r.nearLimit;
                 d["worstQuality"] = r.worstQuality;
                 // The steps they allow, undamped and with the material's
                 // Kelvin-Voigt damping (whether the engine's viscosity is on or not).
                 const double beta = w.pieceBeta(piece);
                 d["stepElastic"] = leapfrogLimit(r.omegaMax, 0.0);
                 d["stepViscous"] = leapfrogLimit(r.omegaMax, 0.5 * beta * r.omegaMax);
                 d["medianElastic"] = leapfrogLimit(r.omegaMedian, 0.0);
                 d["medianViscous"] = leapfrogLimit(r.omegaMedian, 0.5 * beta * r.omegaMedian);
                 return d;
             },
             py::arg("piece"),
             "The piece's stiffest elements at rest against its median one: dict of omegaMax, omegaMedian "
             "[rad/s], elements (up to 10 ids in its mesh's numbering, smallest step first), "
             "elementsNearLimit (steps within 2x of the smallest), worstQuality (min height / longest edge), the "
             "steps stepElastic, stepViscous of the stiffest and medianElastic, medianViscous of the median "
             "element [s] (viscous: with the material's damping).")
        .def("setTetIds",
             [](World& w, int piece, const std::vector<int32_t>& ids) { w.setTetIds(piece, ids); },
             py::arg("piece"), py::arg("ids"),
             "Each element's id in the piece's own mesh numbering (ids[solver's local tet]).")
        .def("tetIds",
             [](const World& w, int piece) {
                 if (piece < 0 || piece >= static_cast<int>(w.pieces.size()))
                     throw InputError(cat("tetIds: no piece ", piece));
                 const PieceInfo& p = w.pieces[piece];
                 std::vector<int32_t> ids;
                 for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) ids.push_back(w.tetId(e));
                 return ids;
             },
             py::arg("piece"), "Each element's id in the piece's own mesh numbering (see setTetIds).")
        .def("stress",
             [](const World& w) {
                 py::array_t<double> a({static_cast<py::ssize_t>(w.nTets()), py::ssize_t(6)});
                 w.computeStress(a.mutable_data());
                 return a;
             },
             "Cauchy stress per tet (xx, yy, zz, yz, xz, xy), elastic plus viscous.")
        .def_property_readonly("energy", [](const World& w) { return energyDict(w.energyTotal()); })
        .def("resetEnergy", [](World& w) { w.resetEnergy(); })
        .def_property_readonly("timings",
                               [](const World& w) {
                                   py::dict d;
                                   for (const auto& [name, v] : w.report().seconds) d[name] = v;
                                   return d;
                               })
        .def_property(
            "gravity", [](const World& w) { return w.gravity; },
            [](World& w, const Eigen::Vector3d& g) { w.setGravity(g); })
        .def_property_readonly("verletRebuilds", &World::verletRebuilds)
        .def_property_readonly("verletWindowSteps", &World::verletWindowSteps,
                               "Steps that built nodes' Verlet lists after the first step of their rebuild "
                               "(verletRebuildSteps > 1 spreads a rebuild over steps).")
        .def_property_readonly("verletWindowOpen", &World::verletWindowOpen,
                               "Is a rebuild of the Verlet lists under way, spread over the next steps?")
        .def("asleep", [](const World& w, int i) { piece(w, i); return w.asleep(i); }, py::arg("piece"),
             "Is the piece asleep (left out of the step until something near it moves)?")
        .def_property_readonly("nAsleep", &World::nAsleep)
        .def("rigid", [](const World& w, int i) { piece(w, i); return w.rigid(i); }, py::arg("piece"),
             "Is the piece moving as a rigid body in its current shape (settings.rigidify)?")
        .def_property_readonly("nRigid", &World::nRigid, "Pieces moving as rigid bodies now (settings.rigidify).")
        .def_property_readonly("rigidSwitches", &World::rigidSwitches,
                               "Switches of pieces between rigid and deformable so far (settings.rigidify).")
        .def("strainRateEstimate", [](const World& w, int i) { piece(w, i); return w.strainRateEstimate(i); },
             py::arg("piece"),
             "The last strain-rate estimate [1/s] of a deformable piece (settings.rigidify): the largest "
             "deviation of its node velocities from their best rigid-body fit over its smallest reference edge.")
        .def("rigidLoadChange", [](const World& w, int i) { piece(w, i); return w.rigidLoadChange(i); },
             py::arg("piece"),
             "A rigid piece's load change since it was made rigid, over its scale (compared with rigidWakeLoad).")
        .def("rigidLoadStrain", [](const World& w, int i) { piece(w, i); return w.rigidLoadStrain(i); },
             py::arg("piece"),
             "The strain a rigid piece's load change since it was made rigid would make if it were deformable: "
             "the change summed over its nodes over 2 E A (compared with rigidWakeStrain).")
        .def_property_readonly("sleepCount", &World::sleepCount, "Pieces put to sleep so far.")
        .def_property_readonly("wakeCount", &World::wakeCount, "Pieces woken so far.")
        .def("wake", [](World& w, int i) { piece(w, i); w.wake(i); }, py::arg("piece"),
             "Wake a sleeping piece (before changing its state from outside).")
        .def("wakeAll", &World::wakeAll)
        .def("dynamic", [](const World& w, int i) { piece(w, i); return w.dynamic(i); }, py::arg("piece"),
             "Is the piece dynamic (moved by the step)?  One that is not stays asleep where it is.")
        .def("setDynamic", [](World& w, int i, bool d) { piece(w, i); w.setDynamic(i, d); }, py::arg("piece"),
             py::arg("dynamic"),
             "False: the piece stops where it is and is left out of the step until set True again "
             "(awake pieces touch it as a fixed body).")
        .def(
            "saveState",
            [](const World& w) {
                py::dict d;
                for (const auto& [name, bytes] : w.saveState().fields)
                    d[py::str(name)] = py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
                return d;
            },
            "The dynamic state (positions, velocities, contact histories, sleeping pieces, clocks, energies) "
            "as a dict of bytes: qdem.saveState writes it to a file.")
        .def(
            "loadState",
            [](World& w, const py::dict& d) {
                WorldState s;
                for (const auto& [k, v] : d) {
                    const std::string b = py::cast<py::bytes>(v);
                    s.fields[py::cast<std::string>(k)] = std::vector<uint8_t>(b.begin(), b.end());
                }
                w.loadState(s);
            },
            py::arg("state"), "Restore a state from saveState() into a world built with the same pieces.")
        .def_property_readonly("contactCounts",
                               [](const World& w) {
                                   py::dict d;
                                   for (const auto& [name, v] : w.report().counts) d[name] = v;
                                   return d;
                               })
        .def_property_readonly(
            "counts",
            [](const World& w) {
                py::dict d;
                for (const auto& [name, v] : w.report().counts) d[name] = v;
                return d;
            },
            "The phases' counters of the last step: contacts by kind (as contactCounts) and "
            "viscousIterations (conjugate-gradient iterations of viscousIntegration='implicit').")
        .def_property_readonly("maxPieceOverlap", &World::maxPieceOverlap)
        .def_property_readonly("maxPieceDepthRatio", &World::maxPieceDepthRatio,
                               "Deepest piece-piece contact of the last step: how far its node (or edge crossing) "
                               "lies behind the other piece's surface, over the contact reach r_a + r_b (0: none "
                               "behind).  Above 1 the step stops with a StabilityError (doc/hard_cases.md).")
        .def(
            "pointPolygonContacts",
            [](const World& w) {
                // (node, triangle, feature) of each point-polygon contact of the last step
                // (history keys are by piece and local triangle: back to global ids)
                const auto& keys = w.pointPolygonKeys();
                const auto& kpiece = w.pointPolygonKeyPieces();
                const auto& triStart = w.surfaceIndex().pieceTriStart;
                std::vector<int32_t> out;
                const int K = PointPolygonKind::kSlots;
                for (std::size_t s = 0; s < w.surfNodes.size(); ++s)
                    for (int k = 0; k < K; ++k) {
                        const int32_t key = keys[K * s + k];
                        if (key >= 0) out.insert(out.end(), {w.surfNodes[s], triStart[kpiece[K * s + k]] + key / 8, key % 8});
                    }
                return copyOut(out, 3);
            },
            "Point-polygon contacts of the last step: rows (node, surface triangle, feature 0 face, 1-3 edge, "
            "4-6 corner).")
        .def(
            "surfaceTriangles",
            [](const World& w) { return copyOut(w.surfaceIndex().tri, 3); },
            "All surface triangles (global node ids), indexed as in pointPolygonContacts.")
        .def_readwrite("time", &World::time)
        .def_readwrite("iter", &World::iter)
        .def_property_readonly("nNodes", &World::nNodes)
        .def_property_readonly("nTets", &World::nTets)
        .def_property_readonly("nPieces", [](const World& w) { return w.pieces.size(); })
        .def_property_readonly("nObstacles", [](const World& w) { return w.obstacles.size(); })
        // Whole-world views (N,3) / (N,) / (T,4) ...
        .def_property_readonly("pos", [](World& w) { return columnView(w.pos, 0, {py::ssize_t(w.nNodes()), 3}); })
        .def_property_readonly("vel", [](World& w) { return columnView(w.vel, 0, {py::ssize_t(w.nNodes()), 3}); })
        .def_property_readonly("refPos",
                               [](World& w) { return columnView(w.refPos, 0, {py::ssize_t(w.nNodes()), 3}, false); })
        .def_property_readonly("force",
                               [](World& w) { return columnView(w.force, 0, {py::ssize_t(w.nNodes()), 3}, false); })
        .def_property_readonly("extForce",
                               [](World& w) { return columnView(w.extForce, 0, {py::ssize_t(w.nNodes()), 3}); })
        .def_property_readonly("mass", [](World& w) { return columnView(w.mass, 0, {py::ssize_t(w.nNodes())}, false); })
        .def_property_readonly("blocked", [](World& w) { return columnView(w.blocked, 0, {py::ssize_t(w.nNodes())}); })
        .def_property_readonly(
            "contactWeight",
            [](const World& w) {
                // Per node (a copy): the area weight of its contact stiffness, 0 inside.
                py::array_t<double> a(py::ssize_t(w.nNodes()));
                auto r = a.mutable_unchecked<1>();
                for (py::ssize_t i = 0; i < r.shape(0); ++i) r(i) = 0.0;
                for (std::size_t s = 0; s < w.surfNodes.size(); ++s) r(w.surfNodes[s]) = w.surfWeight[s];
                return a;
            },
            "Per node: the area weight w = A_i / mean(A) scaling its contact stiffness (0 for interior "
            "nodes; doc/contacts.md, 'Area weights').")
        .def_property_readonly("nodePiece",
                               [](World& w) { return columnView(w.nodePiece, 0, {py::ssize_t(w.nNodes())}, false); })
        .def_property_readonly("tets",
                               [](World& w) { return columnView(w.tetNodes, 0, {py::ssize_t(w.nTets()), 4}, false); })
        .def_property_readonly("tetPiece",
                               [](World& w) { return columnView(w.tetPiece, 0, {py::ssize_t(w.nTets())}, false); })
        .def_property_readonly(
            "tetAddedMass",
            [](World& w) { return columnView(w.tetAddedMass, 0, {py::ssize_t(w.nTets())}, false); })
        .def_property_readonly(
            "tetMaterial",
            [](World& w) { return columnView(w.tetMaterial, 0, {py::ssize_t(w.nTets())}, false); })
        .def_property_readonly("tetVolume",
                               [](World& w) { return columnView(w.tetVol0, 0, {py::ssize_t(w.nTets())}, false); })
        .def(
            "pieceRanges",
            [](const World& w, int i) {
                const PieceInfo& p = piece(w, i);
                return py::make_tuple(p.nodeBegin, p.nodeEnd, p.tetBegin, p.tetEnd);
            },
            py::arg("piece"), "(nodeBegin, nodeEnd, tetBegin, tetEnd) of a piece in the world arrays.")
        .def(
            "pieceSurface",
            [](const World& w, int i) {
                const Surface& s = piece(w, i).surface;
                py::dict d;
                d["triangles"] = copyOut(s.triangles, 3);
                d["edges"] = copyOut(s.edges, 2);
                d["nodes"] = copyOut(s.nodes, 1).reshape({-1});
                d["tets"] = copyOut(s.tets, 1).reshape({-1});
                d["triTet"] = copyOut(s.triTet, 1).reshape({-1});
                return d;
            },
            py::arg("piece"), "Surface of a piece in global node/tet ids (triTet: owner tet of each triangle).")
        .def(
            "pieceMass", [](const World& w, int i) { return piece(w, i).mass; }, py::arg("piece"))
        .def(
            "pieceVolume", [](const World& w, int i) { return piece(w, i).volume; }, py::arg("piece"))
        .def(
            "pieceMaterial", [](const World& w, int i) { return piece(w, i).material; }, py::arg("piece"));
}
