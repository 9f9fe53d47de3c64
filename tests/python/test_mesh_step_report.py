"""What limits the step, named (doc/meshes.md, "What the checks say").

stableDt() names the piece and the elements that set the element step, in
the mesh's own numbering, with how many lie within 2x of the limit, their
worst shape quality (min height / longest edge) and the factor against the
piece's median element; addPiece warns once when that factor passes
qdem.meshchecks.SLIVER_FACTOR.  Every figure is checked against a direct
computation here: the 12x12 stiffness of each element, its largest
eigenvalue over its lumped node mass rho V / 4 (Irons' element bound), the
leapfrog limit 2 / omega.  Meshes are made by the test as users make them:
TetGen (Debian's tetgen) on a triangulated surface with and without its
quality switch, and a boxMesh with one node moved to flatten one element."""
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import qdem
import qdem.scenes.shogi
from qdem import meshchecks

from conftest import lame


def _mat(**kw):
    args = dict(young=1e6, poisson=0.3, density=1100.0, viscosity=0.0, radius=0.004, restitution=0.5)
    args.update(kw)
    return qdem.QdemMat(**args)


def _omega2(nodes, tets, mat):
    """Each element's largest frequency squared on its own lumped mass."""
    lam, mu = lame(mat)
    x = nodes[tets]
    D = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=2)  # edges as columns
    V = np.abs(np.linalg.det(D)) / 6
    B = np.linalg.inv(D)  # rows: gradients of N1..N3
    G = np.concatenate([-B.sum(axis=1, keepdims=True), B], axis=1)
    gg = np.einsum("tai,tbi->tab", G, G)
    K = (lam * np.einsum("tai,tbj->taibj", G, G) + mu * np.einsum("taj,tbi->taibj", G, G)
         + mu * np.einsum("tab,ij->taibj", gg, np.eye(3))).reshape(-1, 12, 12) * V[:, None, None]
    return np.linalg.eigvalsh(K)[:, -1] / (mat.density * V / 4)


def _quality(nodes, tets):
    """Min height / longest edge of each element: 3V / (largest face) / (longest edge)."""
    x = nodes[tets]
    a, b, c, d = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
    v6 = np.abs(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))
    area = np.max([0.5 * np.linalg.norm(np.cross(q - p, r - p), axis=1)
                   for p, q, r in [(b, c, d), (a, c, d), (a, b, d), (a, b, c)]], axis=0)
    edge = np.max([np.linalg.norm(x[:, j] - x[:, i], axis=1) for i in range(4) for j in range(i + 1, 4)], axis=0)
    return v6 / 2 / area / edge


def _direct(nodes, tets, mat):
    """(worst element, count within 2x, worst quality among them, factor of the median step)."""
    w2 = _omega2(nodes, tets, mat)
    steps = 2 / np.sqrt(w2)
    near = np.flatnonzero(w2 >= w2.max() / 4)
    median = np.sort(steps)[len(steps) // 2]  # the n/2-th smallest step
    return int(np.argmax(w2)), len(near), float(_quality(nodes, tets)[near].min()), median / steps.min()


def _stepWarnings(record):
    return [str(w.message) for w in record if "cut its stable step" in str(w.message)]


def _checkReport(d, worst, count, quality, factor):
    assert d["elements"][0] == worst
    assert d["elementsNearLimit"] == count
    assert d["worstQuality"] == pytest.approx(quality, rel=1e-9)
    assert d["medianFactorElastic"] == pytest.approx(factor, rel=1e-9)


# -- a boxMesh with one node moved ---------------------------------------------

def _slivered_box():
    """A 3x3x3-cell boxMesh (5 tets a cell) with an inner node moved 97 % of
    the way to the opposite face of one of its elements: that element
    (returned) becomes the one sliver (the plane of that face holds no other
    face around the node, so no other element flattens), every other stays
    positive."""
    m = qdem.boxMesh((0.3, 0.3, 0.3), (3, 3, 3), tetsPerCell=5)
    x, t = m.nodes.copy(), m.tets
    q0 = _quality(x, t)
    for n in np.flatnonzero(np.all(np.abs(x) < 0.1, axis=1)):
        for e in np.flatnonzero((t == n).any(axis=1)):
            others = [k for k in t[e] if k != n]
            p0, p1, p2 = x[others]
            normal = np.cross(p1 - p0, p2 - p0)
            normal /= np.linalg.norm(normal)
            y = x.copy()
            y[n] -= 0.97 * np.dot(x[n] - p0, normal) * normal
            q = _quality(y, t)
            if np.all(qdem.Mesh(y, t, check=False).volumes() > 0) and np.sort(q)[1] > 0.5 * q0.min():
                return qdem.Mesh(y, t), int(e)
    raise AssertionError("no inner node flattens one element alone")


def test_a_sliver_made_in_a_box_mesh_is_named_with_its_count_quality_and_factor(scene):
    mesh, sliver = _slivered_box()
    mat = _mat()
    worst, count, quality, factor = _direct(mesh.nodes, mesh.tets, mat)
    assert worst == sliver and quality < 0.05 and factor > 10  # the sliver built, as the direct computation sees it
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(mesh, mat, pos=(0, 0, 1))  # reordered by the solver: ids must come back in the mesh's
    d = qdem.stableDt()
    assert d["piece"] == 0
    _checkReport(d, sliver, count, quality, factor)
    assert d["medianElastic"] == pytest.approx(d["elastic"] * factor, rel=1e-9)
    assert "piece 0, tetrahedra %d" % sliver in d["elementLimit"]
    msgs = _stepWarnings(rec)
    assert len(msgs) == 1
    for part in ("%.3g x" % factor, "%d element" % count, "%.3g" % quality, "qdem.improveMesh(mesh)",
                 "targetDt=", "TetGen with -q", "gmsh"):
        assert part in msgs[0], (part, msgs[0])
    # The refusal of a step too large names them too.
    with pytest.raises(qdem._core.StabilityError, match=r"limited by elasticity.*piece 0, tetrahedra %d\b" % sliver):
        qdem.defaultWorld().core.checkDt(2 * d["combined"])


def test_with_viscosity_the_report_gives_both_factors(scene):
    mesh, sliver = _slivered_box()
    mat = _mat(viscosity=200.0)
    with pytest.warns(RuntimeWarning, match=r"cut its stable step [\d.]+ x .*\(with the material's viscosity"):
        qdem.addPiece(mesh, mat, pos=(0, 0, 1))
    d = qdem.stableDt()
    lam, mu = lame(mat)
    beta = mat.viscosity / mu
    w2 = _omega2(mesh.nodes, mesh.tets, mat)
    w = np.sqrt(w2)
    xi = 0.5 * beta * w
    steps = 2 / w * (np.sqrt(1 + xi * xi) - xi)  # the leapfrog limit with damping ratio xi
    assert d["limitedBy"] == "viscosity" and d["elements"][0] == sliver
    assert d["medianFactorViscous"] == pytest.approx(np.sort(steps)[len(steps) // 2] / steps.min(), rel=1e-9)
    assert d["medianFactorViscous"] > d["medianFactorElastic"]


# -- TetGen ------------------------------------------------------------------

def _icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(p) / np.linalg.norm(p) for p in v]
    for _ in range(level):
        mids, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in mids:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                mids[k] = len(v) - 1
            return mids[k]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return np.array(v), np.array(f)


def _tetgen(tmp_path, switches, radius=0.05):
    """A ball's surface (an icosphere of 162 vertices, radii jittered by
    0.5 %, as a scan's would be) meshed by TetGen with `switches`: the
    path of its .ele file."""
    if shutil.which("tetgen") is None:
        pytest.skip("TetGen is not installed (Debian: apt install tetgen)")
    v, f = _icosphere(2)
    v = v * (1 + 0.005 * np.random.default_rng(3).uniform(-1, 1, (len(v), 1))) * radius
    off = tmp_path / "ball.off"
    with open(off, "w") as o:
        o.write("OFF\n%d %d 0\n" % (len(v), len(f)))
        o.writelines("%.17g %.17g %.17g\n" % tuple(p) for p in v)
        o.writelines("3 %d %d %d\n" % tuple(t) for t in f)
    subprocess.run(["tetgen", switches + "Q", str(off)], check=True, capture_output=True)
    return str(tmp_path / "ball.1.ele")


def test_tetgen_without_quality_leaves_slivers_that_are_named_and_warned_of(scene, tmp_path):
    path = _tetgen(tmp_path, "-p")
    mesh, mat = qdem.loadMesh(path), _mat()
    worst, count, quality, factor = _direct(mesh.nodes, mesh.tets, mat)
    assert factor > 10 and quality < 0.01  # what TetGen left, computed directly
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(path, mat, pos=(0, 0, 1))
    msgs = _stepWarnings(rec)
    assert len(msgs) == 1 and "%.3g x" % factor in msgs[0] and "tetrahedra %d" % worst in msgs[0]
    _checkReport(qdem.stableDt(), worst, count, quality, factor)


def test_tetgen_with_quality_gives_no_warning(scene, tmp_path):
    path = _tetgen(tmp_path, "-pq")
    mesh, mat = qdem.loadMesh(path), _mat()
    worst, count, quality, factor = _direct(mesh.nodes, mesh.tets, mat)
    assert factor < meshchecks.SLIVER_FACTOR
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(path, mat, pos=(0, 0, 1))
    assert _stepWarnings(rec) == []
    _checkReport(qdem.stableDt(), worst, count, quality, factor)


@pytest.mark.parametrize("make", [
    lambda: qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)),
    lambda: qdem.boxMesh((0.1, 0.2, 0.1), (3, 7, 2), tetsPerCell=5),
    lambda: qdem.ballMesh(0.05, 0.012),
    lambda: qdem.ballMesh(0.15, 0.075),
    lambda: qdem.scenes.shogi.mesh("king"),
    lambda: qdem.scenes.shogi.mesh("pawn"),
], ids=["box", "box5", "ball", "coarseBall", "shogiKing", "shogiPawn"])
def test_good_meshes_give_no_warning(scene, make):
    mesh, mat = make(), _mat(viscosity=50.0)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(mesh, mat, pos=(0, 0, 1))
    assert _stepWarnings(rec) == []
    d = qdem.stableDt()
    assert d["medianFactorElastic"] < meshchecks.SLIVER_FACTOR and d["piece"] == 0


def test_the_limiting_piece_is_the_one_with_the_smallest_element_step(scene):
    mat = _mat()
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), mat, pos=(0, 0, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh, sliver = _slivered_box()
        qdem.addPiece(mesh, mat, pos=(1, 0, 1))
    d = qdem.stableDt()
    assert d["piece"] == 1 and d["elements"][0] == sliver


def test_a_saved_and_loaded_scene_names_the_same_elements(scene):
    """O.save keeps each element's id in its mesh's numbering: a scene loaded
    into an emptied world (O.reset, then O.loadTmp) names the same sliver."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh, sliver = _slivered_box()
        qdem.addPiece(mesh, _mat(), pos=(0, 0, 1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    before = qdem.stableDt()
    O.saveTmp("sliver")
    O.reset()
    assert len(qdem.defaultWorld().pieces) == 0
    O.loadTmp("sliver")
    after = qdem.stableDt()
    assert after["elements"] == before["elements"] and after["elements"][0] == sliver
    assert after["medianFactorElastic"] == before["medianFactorElastic"]
