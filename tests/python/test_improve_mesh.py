"""qdem.improveMesh removes the slivers of a mesh a user brings and keeps its
shape.  The meshes are made here: a closed surface filled by Debian's TetGen
without its quality switch (``tetgen -p``), which leaves slivers (a box with
irregular face triangles, a cylinder with sharp rims, a bumpy ball).

Asserted: the worst element cuts the elastic step more than 10x against the
median one before, at most 3x after, with the step from qdem's own
stableDt() (a world holding the piece, against a world holding its median
element alone); the volume within 1 %; the surface within a fraction of the
cell size; the box's faces flat, its corners and edges where they were; the
cylinder's rims sharp; the result passes the mesh checks and a piece of it
dropped on a floor comes to rest on it with the default law."""
import numpy as np
import pytest

import qdem
import qdem.modes
from qdem import _core

import sliver_meshes as sm

pytestmark = pytest.mark.skipif(not (getattr(_core, "haveCgal", False) and sm.haveTetgen()),
                                reason="needs CGAL and Debian's tetgen")

BOX = np.array([0.2, 0.1, 0.1])
R, H = 0.05, 0.1
MAT = dict(young=1e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.005)


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("tetgen")
    box = sm.tetgenMesh(*sm.boxSurface(BOX, 0.02), d, "box")
    cyl = sm.tetgenMesh(*sm.cylinderSurface(R, H, 32), d, "cylinder")
    ball = sm.tetgenMesh(*sm.bumpyBallSurface(0.05, 3, 0.06), d, "ball")
    return {name: (m, qdem.improveMesh(m)) for name, m in (("box", box), ("cylinder", cyl), ("ball", ball))}


def _elasticDt(mesh, mat=None, kind="elastic"):
    w = qdem.World()
    w.addPiece(mesh, mat or qdem.QdemMat(**MAT))
    return w.stableDt()[kind]


def _medianElementDt(mesh, mat=None, kind="elastic"):
    """qdem's stable step for the mesh's median element (by the length that
    sets its step) alone: what the median element allows."""
    he = qdem.remesh.elementSizes(mesh.nodes, mesh.tets)
    t = int(np.argsort(he)[len(he) // 2])
    return _elasticDt(qdem.Mesh(mesh.nodes[mesh.tets[t]], np.array([[0, 1, 2, 3]])), mat, kind)


@pytest.mark.parametrize("name", ["box", "cylinder", "ball"])
def test_the_step_goes_from_slivers_to_the_median_element(meshes, name):
    before, after = meshes[name]
    dtMedian = _medianElementDt(after)
    # Before: TetGen's slivers cut the step more than 10x.
    assert _elasticDt(before) < dtMedian / 10
    assert meshes[name][1].improveReport["before"]["stepFactor"] > 10
    # After: within 3x of what the median element allows, by qdem's stableDt.
    assert _elasticDt(after) > dtMedian / 3, "step %.3g s, median element %.3g s" % (_elasticDt(after), dtMedian)
    assert after.improveReport["after"]["stepFactor"] < 3
    after.check()  # qdem's mesh checks
    assert after.nodeIds is None  # numbering is not kept (documented)


@pytest.mark.parametrize("name, maxDev", [("box", 1e-9), ("cylinder", 0.1), ("ball", 0.25)])
def test_the_volume_and_surface_are_kept(meshes, name, maxDev):
    before, after = meshes[name]
    rep = after.improveReport
    assert after.volumes().sum() == pytest.approx(before.volumes().sum(), rel=0.01)
    assert rep["volumeChange"] == pytest.approx(after.volumes().sum() / before.volumes().sum() - 1, abs=1e-12)
    assert rep["deviationPerCell"] <= maxDev


def test_the_box_keeps_flat_faces_sharp_edges_and_corners(meshes):
    _, m = meshes["box"]
    h = m.improveReport["cellSize"]
    half = BOX / 2
    surf = m.surface()
    b = m.nodes[surf["nodes"]]
    # every boundary node on a face of the box
    assert np.abs((half - np.abs(b)).min(axis=1)).max() < 1e-12
    # the eight corners are nodes
    for c in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3):
        assert np.linalg.norm(m.nodes - c * half, axis=1).min() < 1e-12
    # the sharp edges of the result are the box's twelve edges, whole
    e = _core.boundaryFeatureEdges(m.nodes, m.tets, 40.0)
    a, c = m.nodes[e[:, 0]], m.nodes[e[:, 1]]
    onEdge = (np.isclose(np.abs(a), half, atol=1e-12) & np.isclose(np.abs(c), half, atol=1e-12)).sum(axis=1) >= 2
    assert onEdge.all()
    assert np.linalg.norm(a - c, axis=1).sum() == pytest.approx(4 * BOX.sum(), rel=1e-12)
    assert m.improveReport["featureEdges"] > 0 and m.improveReport["corners"] == 8
    assert m.improveReport["maxDeviation"] < 1e-3 * h


def test_the_cylinder_keeps_its_rims(meshes):
    _, m = meshes["cylinder"]
    e = _core.boundaryFeatureEdges(m.nodes, m.tets, 40.0)
    p = m.nodes[e.ravel()]
    assert np.abs(np.abs(p[:, 2]) - H / 2).max() < 1e-12
    r = np.hypot(p[:, 0], p[:, 1])
    assert r.min() > R * np.cos(np.pi / 32) - 1e-12 and r.max() < R + 1e-12  # on the input's 32-gon
    # both rims, all round: the feature edges add up to two 32-gon perimeters
    length = np.linalg.norm(m.nodes[e[:, 0]] - m.nodes[e[:, 1]], axis=1).sum()
    assert length == pytest.approx(2 * 64 * R * np.sin(np.pi / 32), rel=1e-9)


def test_an_improved_mesh_drops_and_rests_on_a_floor(scene, meshes):
    """The improved box, dropped flat with the default material law, comes to
    rest on a YADE floor that carries its weight.  Viscosity is integrated
    implicitly (the damping then costs no step: the step is the elastic one,
    within 3x of the median element's); explicitly, the viscous limit goes
    as the element size squared and is within 3^2 of the median element's."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    _, m = meshes["box"]
    mat = qdem.QdemMat(**MAT)
    mat.viscosity = qdem.modes.viscosityForDamping(m, mat, 0.3)
    piece = qdem.addPiece(m, mat, pos=(0, 0, BOX[2] / 2 + 0.005))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1, viscousIntegration="implicit"),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    dt = O.engines[1].stableDt()
    assert dt["combinedExplicit"] > _medianElementDt(m, mat, "combined") / 9
    O.dt = 0.8 * dt["combined"]
    assert O.dt > 0.8 * _medianElementDt(m, mat, "elastic") / 3
    O.run(int(0.5 / O.dt), True)
    force = []
    for _ in range(20):  # the floor's load, averaged over the last 0.05 s
        O.run(int(0.0025 / O.dt), True)
        force.append(O.forces.f(floor)[2])
    assert np.isfinite(piece.pos).all()
    assert np.abs(piece.vel).max() < 5e-3, "not at rest"
    zmin = piece.pos[:, 2].min()
    assert -0.005 < zmin < 0.005  # on the floor (within the contact radius), not through it
    assert np.mean(force) == pytest.approx(-piece.totalMass * 9.81, rel=0.01)  # it carries the weight


def test_bad_input_and_broken_tolerances_are_refused(meshes):
    before, _ = meshes["cylinder"]
    with pytest.raises(ValueError, match="departs from the input's .* smaller cellSize"):
        qdem.improveMesh(before, maxDeviation=0.01)
    with pytest.raises(ValueError, match="volume differs .* smaller cellSize"):
        qdem.improveMesh(before, maxVolumeChange=1e-4)
    with pytest.raises(ValueError, match="cellSize must be"):
        qdem.improveMesh(before, cellSize=-1)
    inverted = before.tets.copy()
    inverted[0, [2, 3]] = inverted[0, [3, 2]]
    with pytest.raises(ValueError, match="inverted|negative"):
        qdem.improveMesh((before.nodes, inverted))


def test_a_flat_sliver_lying_on_the_surface_is_removed():
    """A tet of height 1e-5 x its edges glued onto a face of a box (three of
    its faces on the surface, all four nodes on it): the surface vertices
    move, so it goes; the surface moves by its height only."""
    box = qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4))
    surf = box.surface()
    tri = surf["triangles"][np.flatnonzero(np.isclose(box.nodes[surf["triangles"]][:, :, 2], 0.05).all(axis=1))[0]]
    apex = box.nodes[tri].mean(axis=0) + (0, 0, 1e-5 * 0.025)
    nodes = np.vstack([box.nodes, apex])
    tets = np.vstack([box.tets, [[tri[0], tri[1], tri[2], len(box.nodes)]]])
    tets[-1, [1, 2]] = tets[-1, [2, 1]] if qdem.Mesh(nodes, tets, check=False).volumes()[-1] < 0 else tets[-1, [1, 2]]
    m = qdem.Mesh(nodes, tets)
    assert qdem.meshQuality(m)["stepFactor"] > 1000
    out = qdem.improveMesh(m)
    rep = out.improveReport
    assert rep["after"]["stepFactor"] < 3
    assert out.volumes().sum() == pytest.approx(1e-3, rel=1e-9)
    assert rep["maxDeviation"] < 1e-6
