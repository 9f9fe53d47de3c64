"""Wrong arguments get a clear error naming the argument and what it must be,
before anything is added or written (never a bare NumPy/pybind error, a
half-added piece, a silently changed value or a broken output file)."""
import os

import numpy as np
import pytest

import qdem

from conftest import rubber


def _cube():
    return qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2))


def _untouched(w):
    assert w.core.nPieces == 0 and w.core.nNodes == 0 and w.pieces == []


@pytest.mark.parametrize("kw, words", [
    (dict(vel=(0, -1)), ["vel", "3 numbers"]),
    (dict(vel=(1, 2, 3, 4)), ["vel", "3 numbers"]),
    (dict(vel="abc"), ["vel", "3 numbers"]),
    (dict(vel=None), ["vel", "3 numbers"]),
    (dict(vel=(0, float("nan"), 0)), ["vel", "not finite"]),
    (dict(angVel=(1, 2, 3, 4)), ["angVel", "3 numbers"]),
    (dict(angVel=(0, 0)), ["angVel", "3 numbers"]),
    (dict(angVel=("a", 0, 0)), ["angVel", "3 numbers"]),
    (dict(angVel=(0, 0, float("inf"))), ["angVel", "not finite"]),
    (dict(pos="xyz"), ["pos", "3 numbers"]),
    (dict(pos=(1, 2)), ["pos", "3 numbers"]),
    (dict(pos=(1, float("nan"), 2)), ["pos", "not finite"]),
    (dict(ori="z"), ["ori", "Quaternion"]),
    (dict(ori=(1, 0, 0, 0)), ["ori", "Quaternion"]),
    (dict(ori=((0, 1), 0.5)), ["axis", "3 numbers"]),
    (dict(ori=((0, float("nan"), 1), 0.5)), ["axis", "not finite"]),
    (dict(ori=((0, 0, 1), "half")), ["angle", "number"]),
    (dict(ori=((0, 0, 1), float("inf"))), ["angle", "not finite"]),
    (dict(ori=(0.5, (0, 0, 1))), ["axis first"]),
    (dict(ori=((0, 0, 0), 0.5)), ["axis", "non-zero"]),
    (dict(ori=np.eye(3) * 1.0000001), ["not a rotation"]),
    (dict(ori=np.eye(3) * (1 + 1e-6)), ["not a rotation"]),
    (dict(ori=np.diag([1.0, 1, -1])), ["reflection"]),
])
def test_addpiece_refuses_bad_arguments_before_adding_anything(kw, words):
    """Before: vel=(0, -1) or angVel of 4 numbers raised NumPy's 'cannot reshape'
    after the piece was in the compiled world: a hidden piece that interacted."""
    w = qdem.World()
    mat = rubber()
    with pytest.raises(ValueError) as e:
        qdem.addPiece(_cube(), mat, world=w, **kw)
    for word in words:
        assert word in str(e.value)
    assert "addPiece" in str(e.value)
    _untouched(w)
    mat.young = 2e7  # not locked by the refused call
    qdem.addPiece(_cube(), mat, world=w)  # the world still works
    assert w.core.nPieces == 1 and len(w.pieces) == 1


def test_quaternion_zero_or_nan_is_refused():
    from yade import Quaternion
    w = qdem.World()
    with pytest.raises(ValueError, match="Quaternion.*zero norm"):
        qdem.addPiece(_cube(), rubber(), ori=Quaternion(0, 0, 0, 0), world=w)
    with pytest.raises(ValueError, match="ori \\(Quaternion\\).*not finite"):
        qdem.addPiece(_cube(), rubber(), ori=Quaternion(float("nan"), 0, 0, 1), world=w)
    _untouched(w)
    # a non-unit quaternion is normalised: a quarter turn about z
    p = qdem.addPiece(_cube(), rubber(), ori=Quaternion(2, 0, 0, 2), world=w)
    q = qdem.addPiece(_cube(), rubber(), pos=(1, 0, 0), ori=((0, 0, 1), np.pi / 2), world=w)
    assert np.allclose(np.asarray(p.pos) + (1, 0, 0), np.asarray(q.pos), atol=1e-12)


def test_orientation_as_list_equals_tuple_and_matrix():
    w = qdem.World()
    a = qdem.addPiece(_cube(), rubber(), ori=((0, 0, 1), 0.5), world=w)
    b = qdem.addPiece(_cube(), rubber(), ori=[(0, 0, 1), 0.5], world=w)
    c = qdem.addPiece(_cube(), rubber(), ori=[[0, 0, 1], 0.5], world=w)
    R = qdem.world.rotationMatrix(((0, 0, 1), 0.5))
    d = qdem.addPiece(_cube(), rubber(), ori=R.tolist(), world=w)
    for p in (b, c, d):
        assert np.allclose(np.asarray(a.pos), np.asarray(p.pos), atol=1e-14)


def test_refused_mesh_does_not_lock_its_material_or_leave_nodes():
    """Before: a mesh with an unused node was refused after the compiled world
    had grown its node arrays (a hidden node) and the material stayed locked."""
    w = qdem.World()
    m = _cube()
    mat = rubber()
    with pytest.raises(ValueError, match="belongs to no tetrahedron"):
        qdem.addPiece(qdem.Mesh(np.vstack([m.nodes, [[5, 5, 5]]]), m.tets), mat, world=w)
    _untouched(w)
    with pytest.raises(ValueError, match="inverted"):
        qdem.addPiece(m.scaled(-1), mat, world=w)
    _untouched(w)
    mat.young = 3e7  # still editable
    p = qdem.addPiece(m, mat, world=w)
    assert w.core.nNodes == len(p.pos) == m.nNodes
    assert w.stableDt()["elastic"] > 0


def _hexBar(path):
    """A 2 m long bar: the unit tet cube [-.5,.5]^3 and one hexahedron beside it."""
    import meshio
    b = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    N, T = b.nodes, b.tets
    h = np.array([[.5, -.5, -.5], [1.5, -.5, -.5], [1.5, .5, -.5], [.5, .5, -.5],
                  [.5, -.5, .5], [1.5, -.5, .5], [1.5, .5, .5], [.5, .5, .5]])
    idx = []
    for k, p in enumerate(h):
        d = np.linalg.norm(N - p, axis=1)
        idx.append(int(d.argmin()) if d.min() < 1e-12 else len(N) + k)
    return meshio.Mesh(np.vstack([N, h]), [("tetra", T), ("hexahedron", np.array([idx]))])


def test_loadmesh_refuses_volume_cells_that_are_not_linear_tets(tmp_path):
    """Before: the hexahedron (or wedge, pyramid) was dropped silently: half the body."""
    import meshio
    m = _hexBar(tmp_path)
    m.write(str(tmp_path / "mixed.vtu"))
    with pytest.raises(ValueError, match=r"1 hexahedron \(and 48 linear tetra\).*Re-mesh into linear tetrahedra"):
        qdem.loadMesh(str(tmp_path / "mixed.vtu"))
    m2 = meshio.Mesh(m.points, [("hexahedron", m.cells[1].data), ("tetra", m.cells[0].data),
                                ("wedge", np.array([[0, 1, 2, 3, 4, 5]])), ("pyramid", np.array([[0, 1, 2, 3, 4]]))])
    m2.write(str(tmp_path / "mixed.msh"), file_format="gmsh22")
    with pytest.raises(ValueError, match="1 hexahedron, 1 pyramid, 1 wedge.*gmsh"):
        qdem.loadMesh(str(tmp_path / "mixed.msh"))
    # quadratic tetrahedra: named, with the fix (ElementOrder 1)
    b = qdem.boxMesh((1, 1, 1), (1, 1, 1))
    P, mid = list(map(tuple, b.nodes)), {}

    def midp(a, c):
        k = (min(a, c), max(a, c))
        if k not in mid:
            mid[k] = len(P)
            P.append(tuple((b.nodes[a] + b.nodes[c]) / 2))
        return mid[k]
    T10 = [list(t) + [midp(t[0], t[1]), midp(t[1], t[2]), midp(t[0], t[2]), midp(t[0], t[3]), midp(t[1], t[3]),
                      midp(t[2], t[3])] for t in b.tets]
    meshio.Mesh(np.array(P), [("tetra10", np.array(T10))]).write(str(tmp_path / "quad.vtu"))
    with pytest.raises(ValueError, match=r"6 tetra10.*ElementOrder = 1"):
        qdem.loadMesh(str(tmp_path / "quad.vtu"))


def test_loadmesh_ignores_boundary_cells_and_refuses_flat_meshes(tmp_path):
    import meshio
    b = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    meshio.Mesh(b.nodes, [("tetra", b.tets), ("triangle", np.array([[0, 1, 2]])), ("line", np.array([[0, 1]])),
                          ("vertex", np.array([[0]]))]).write(str(tmp_path / "tags.vtu"))
    assert qdem.loadMesh(str(tmp_path / "tags.vtu")).nTets == b.nTets
    # a 2-D mesh: tets whose points have x, y only (written with z = 0)
    meshio.Mesh(b.nodes[:, :2], [("tetra", b.tets)]).write(str(tmp_path / "flat.vtu"))
    with pytest.raises(ValueError, match="every node .* has z = 0: the mesh is flat"):
        qdem.loadMesh(str(tmp_path / "flat.vtu"))
    meshio.Mesh(np.array([[0, 0], [1, 0], [0, 1.0]]), [("triangle", np.array([[0, 1, 2]]))]).write(
        str(tmp_path / "tri2d.vtu"))
    with pytest.raises(ValueError, match="no tetrahedra .*triangle.*no volume"):
        qdem.loadMesh(str(tmp_path / "tri2d.vtu"))


@pytest.mark.parametrize("scale", [0, -1, float("nan"), "1", (1, 1), (1, 1, -2), True])
def test_loadmesh_refuses_bad_scale(tmp_path, scale):
    """Before: scale=-1 said 'inverted, use fixOrientation', scale=0 'zero volume'."""
    import meshio
    b = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    meshio.Mesh(b.nodes, [("tetra", b.tets)]).write(str(tmp_path / "b.vtu"))
    with pytest.raises(ValueError, match="scale must be a finite number > 0"):
        qdem.loadMesh(str(tmp_path / "b.vtu"), scale=scale)
    assert np.allclose(qdem.loadMesh(str(tmp_path / "b.vtu"), scale=(1, 1, 2)).bounds()[1], (.5, .5, 1))


_CUBE_V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
_CUBE_F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                    [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


@pytest.mark.skipif(not getattr(qdem._core, "haveCgal", False), reason="built without CGAL")
def test_meshsurface_refuses_a_plate_thinner_than_its_cells_at_once():
    """Before: a 1 x 1 x 0.001 plate with cellSize 0.1 ran two minutes in CGAL and
    then reported a non-manifold node."""
    import time
    t0 = time.time()
    with pytest.raises(ValueError, match=r"too thin for cellSize 0.1: parts of it are 0.001\d* thick .*need "
                                         r"tetrahedra of about 0.00033.*Thicken those parts, or mesh a plate as "
                                         r"qdem.boxMesh"):
        qdem.meshSurface((_CUBE_V * (1, 1, 1e-3), _CUBE_F), 0.1)
    with pytest.raises(ValueError, match=r"too thin for surfaceSize 0.1"):
        qdem.meshSurface((_CUBE_V * (1, 1, 1e-3), _CUBE_F), 0.01, surfaceSize=0.1)
    assert time.time() - t0 < 5
    # a plate CGAL failed on (non-manifold) gets cells of half its thickness
    plate = qdem.meshSurface((_CUBE_V * (0.3, 0.3, 0.035), _CUBE_F), 0.1)
    assert plate.volumeKept == pytest.approx(1, abs=1e-6) and plate.meshReport["thinnest"] == pytest.approx(0.035)
    # thick enough, and a body smaller than one cell, still mesh
    assert qdem.meshSurface((_CUBE_V * (0.3, 0.3, 0.05), _CUBE_F), 0.1).nTets > 0
    assert abs(qdem.meshSurface((_CUBE_V, _CUBE_F), 10).volumes().sum() - 1) < 1e-12


def _recordedScene(O, fileBase, steps=10):
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(_cube(), rubber(viscosity=1.0))
    rec = qdem.VtkRecorder(fileBase=fileBase, iterPeriod=np.int64(5))
    O.engines = [ForceResetter(), qdem.QdemEngine(), rec, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(steps, True)
    return rec


def test_recorder_pvd_escapes_xml_characters(scene, tmp_path):
    """Before: fileBase 'a&b<c"d-' wrote file="a&b<c"d-000000.vtu" into the .pvd: broken XML."""
    import xml.etree.ElementTree as ET
    rec = _recordedScene(scene, str(tmp_path / "a&b<c\"d'e-"))
    assert rec.pvdPath() == str(tmp_path / "a&b<c\"d'e.pvd")
    root = ET.parse(rec.pvdPath()).getroot()
    files = [d.get("file") for d in root.iter("DataSet")]
    assert files == ["a&b<c\"d'e-%06d.vtu" % i for i in (0, 5, 10)]
    for f in files:
        assert os.path.isfile(tmp_path / f)


def test_recorder_directory_filebase_gets_a_visible_pvd(scene, tmp_path):
    """Before: fileBase 'out/run/' kept its collection in a hidden 'out/run/.pvd'."""
    rec = _recordedScene(scene, str(tmp_path / "run") + "/")
    assert sorted(os.listdir(tmp_path / "run")) == ["000000.vtu", "000005.vtu", "000010.vtu", "frames.pvd"]
    assert rec.pvdPath() == str(tmp_path / "run" / "frames.pvd")


def test_recorder_reports_an_unwritable_filebase(scene, tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(OSError, match=r"VtkRecorder: cannot write the frame .*fileBase="):
        _recordedScene(scene, str(tmp_path / "afile" / "x-"))


@pytest.mark.parametrize("kw, words", [
    (dict(fileBase=5), "fileBase=5 is invalid: must be a path prefix"),
    (dict(fileBase=None), "fileBase=None is invalid: must be a path prefix"),
    (dict(fileBase=""), "fileBase='' is invalid: must not be empty"),
    (dict(iterPeriod=-1), "iterPeriod=-1 is invalid: must be an integer >= 0"),
    (dict(iterPeriod=2.5), "iterPeriod=2.5 is invalid: must be an integer"),
    (dict(iterPeriod=True), "iterPeriod=True is invalid: must be an integer"),
    (dict(iterPeriod="10"), "iterPeriod='10' is invalid: must be an integer"),
    (dict(virtPeriod=float("inf")), "virtPeriod=inf is invalid: must be a number >= 0"),
    (dict(virtPeriod="0.1"), "virtPeriod='0.1' is invalid: must be a number >= 0"),
])
def test_recorder_settings_are_checked_at_construction(kw, words):
    """Before: fileBase=5 was accepted and failed at the first step."""
    with pytest.raises(ValueError) as e:
        qdem.VtkRecorder(**kw)
    assert words in str(e.value)


def test_recorder_takes_numpy_numbers_as_plain_ones(tmp_path):
    """Before: iterPeriod=np.int64(10) was refused ('must be a number >= 0')."""
    import json
    import pathlib
    r = qdem.VtkRecorder(fileBase=pathlib.Path(tmp_path) / "f-", iterPeriod=np.int64(10),
                         virtPeriod=np.float32(0.5))
    assert r.iterPeriod == 10 and type(r.iterPeriod) is int
    assert type(r.virtPeriod) is float and r.fileBase == str(tmp_path / "f-")
    assert qdem.VtkRecorder(iterPeriod=20.0).iterPeriod == 20
    json.dumps(r.dict())  # what O.save stores


@pytest.mark.parametrize("kw, words", [
    (dict(progressPeriod=-1), "progressPeriod=-1 is invalid: must be an integer >= 0 (0 = silent)"),
    (dict(progressPeriod=0.5), "progressPeriod=0.5 is invalid: must be an integer"),
    (dict(checkPeriod=-5), "checkPeriod=-5 is invalid: must be an integer >= 0 (0 = never)"),
    (dict(checkPeriod=2.5), "checkPeriod=2.5 is invalid: must be an integer"),
    (dict(checkPeriod="x"), "checkPeriod='x' is invalid: must be an integer"),
    (dict(threads=-1), "threads=-1 is invalid: must be an integer >= 0"),
    (dict(threads=2.5), "threads=2.5 is invalid: must be an integer"),
    (dict(threads=True), "threads=True is invalid: must be an integer"),
    (dict(gatherPeriod="1"), "gatherPeriod='1' is invalid: must be an integer >= 0"),
    (dict(sphereMask=1.5), "sphereMask=1.5 is invalid: must be an integer"),
    (dict(sphereMargin="0.1"), "sphereMargin='0.1' is invalid: must be a number in [0.01, 10]"),
    (dict(couple="no"), "couple='no' is invalid: must be True or False"),
    (dict(checkDt="False"), "checkDt='False' is invalid: must be True or False"),
    (dict(spheres=2), "spheres=2 is invalid: must be True or False"),
    (dict(friction="off"), "friction='off' is invalid: must be True or False"),
    (dict(pointPolygon=None), "pointPolygon=None is invalid: must be True or False"),
    (dict(damping="0.1"), "damping='0.1' is invalid"),
])
def test_engine_settings_are_checked_at_assignment(kw, words):
    """Before: progressPeriod=-1 printed every step, checkPeriod='x' raised a raw
    TypeError at step 100, couple='no' counted as True."""
    with pytest.raises(ValueError) as e:
        qdem.QdemEngine(**kw)
    assert words in str(e.value)
    e = qdem.QdemEngine()
    (k, v), = kw.items()
    before = getattr(e, k)
    with pytest.raises(ValueError):
        setattr(e, k, v)
    assert getattr(e, k) == before


def test_engine_settings_take_numpy_and_yade_style_values():
    e = qdem.QdemEngine(checkPeriod=np.int64(50), threads=np.int32(1), progressPeriod=1000.0, couple=0,
                        checkDt=np.bool_(True), sphereMask=np.int64(-1), damping=np.float32(0.25))
    assert (e.checkPeriod, e.threads, e.progressPeriod, e.couple, e.checkDt, e.sphereMask) == (50, 1, 1000, False,
                                                                                                True, -1)
    assert all(type(getattr(e, k)) is int for k in ("checkPeriod", "threads", "progressPeriod", "sphereMask"))
    assert type(e.couple) is bool and e.damping == 0.25
    h = qdem.QdemEngine.__doc__
    assert "checkPeriod (= 100)" in h and "couple (= True)" in h and "progressPeriod (= 0)" in h


@pytest.mark.parametrize("kw, words", [
    (dict(young="1e6"), "young='1e6' is invalid: must be a number > 0"),
    (dict(young=True), "young=True is invalid: must be a number > 0"),
    (dict(poisson="0.3"), "poisson='0.3' is invalid: must be a number in (-1, 0.5)"),
    (dict(restitution=False), "restitution=False is invalid: must be a number in (0, 1]"),
    (dict(density=[1000]), "density=[1000] is invalid: must be a number > 0"),
    (dict(law=["stableNeoHookean"]), "law=['stableNeoHookean'] is invalid: must be one of"),
])
def test_material_refuses_strings_and_bools(kw, words):
    """Before: young='1e6' raised a raw TypeError, young=True made E = 1 Pa."""
    with pytest.raises(ValueError) as e:
        qdem.QdemMat(**kw)
    assert words in str(e.value)


def test_material_keeps_numpy_numbers_as_floats():
    import json
    m = qdem.QdemMat(young=np.float32(1e6), density=np.int64(1000), poisson=0.25)
    assert type(m.young) is float and type(m.density) is float and m.young == 1e6
    json.dumps(m.dict())  # what O.save stores


@pytest.mark.parametrize("args, words", [
    (((1, 1, 1), (2.7, 2, 2)), "cells must be an integer >= 1 or 3 of them"),
    (((1, 1, 1), (2, 2, 2), 6.9), "tetsPerCell must be 5, 6 or 12, got 6.9"),
    (((1, 1, 1), (2, 2, 2), True), "tetsPerCell must be 5, 6 or 12"),
    (((1, 1, 1), (True, 2, 2)), "cells must be an integer"),
    (((1, 1, 1), "222"), "cells must be an integer"),
    (((1, 1, 1), (0, 2, 2)), "cells must be integers >= 1, got 0x2x2"),
    (((float("inf"), 1, 1), (2, 2, 2)), "size must be a finite number > 0"),
    (((float("nan"), 1, 1), (2, 2, 2)), "size must be a finite number > 0"),
    (((-1, 1, 1), (2, 2, 2)), "size must be a finite number > 0"),
    (((1, 1), (2, 2, 2)), "size must be a finite number > 0 or 3 of them"),
    (("1", 1, 1), "size must be"),
    (((1e300,) * 3, (2, 2, 2)), "cells of volume inf, beyond the range"),
    (((1e-300,) * 3, (2, 2, 2)), "cells of volume 0, beyond the range"),
    (((1, 1, 1), (2**31, 1, 1)), "beyond the 32-bit indices"),
    (((1, 1, 1), (2**32 + 2, 1, 1)), "beyond the 32-bit indices"),
    (((1, 1, 1), (1300, 1300, 1300)), "beyond the 32-bit indices"),
])
def test_boxmesh_checks_its_arguments(args, words):
    """Before: cells=2.7 and tetsPerCell=6.9 were truncated silently, size inf gave
    infinite nodes, 1e300 NaN volumes, 2**31 cells a raw pybind TypeError."""
    with pytest.raises(ValueError) as e:
        qdem.boxMesh(*args)
    assert words in str(e.value) and "boxMesh" in str(e.value)


def test_boxmesh_takes_integral_and_numpy_counts():
    a = qdem.boxMesh((1, 1, 1), (2, 2, 2), 6)
    for cells, tpc in (((2.0, 2, 2), 6.0), (np.array([2, 2, 2]), np.int64(6)), (2, 6), (np.int32(2), 6)):
        b = qdem.boxMesh(np.array([1.0, 1, 1]), cells, tpc)
        assert np.array_equal(a.nodes, b.nodes) and np.array_equal(a.tets, b.tets)
    assert qdem.boxMesh(2.0, 1).bounds()[1].tolist() == [1, 1, 1]


def test_mesh_refuses_indices_that_would_wrap_to_32_bits():
    """Before: tets + 2**32 (int64) wrapped through astype(int32) back onto valid nodes."""
    m = _cube()
    for tets in (m.tets.astype(np.int64) + 2**32, m.tets.astype(np.uint64) + 2**31):
        with pytest.raises(ValueError, match=r"tetrahedron 0 refers to node \d{10} but the mesh has 27 nodes"):
            qdem.Mesh(m.nodes, tets)
        with pytest.raises(ValueError, match="refers to node"):
            qdem.Mesh(m.nodes, tets, check=False)
    assert qdem.Mesh(m.nodes, m.tets.astype(np.uint64)).nTets == m.nTets
    with pytest.raises(ValueError, match="real coordinates"):
        qdem.Mesh(m.nodes.astype(complex), m.tets)


def test_mesh_out_of_floating_point_range_is_named():
    """Before: a mesh in units 1e200 times too large was refused as 'node 0 belongs to no tetrahedron'."""
    m = _cube()
    w = qdem.World()
    with pytest.raises(ValueError, match="node 0 gets mass .*out of floating point range"):
        qdem.addPiece(qdem.Mesh(m.nodes * 1e200, m.tets, check=False), rubber(), world=w)
    _untouched(w)


def test_piece_dynamic_takes_a_flag_only():
    """Piece.dynamic = 'no' counted as True (the piece stayed dynamic), as
    engine flags do no more: refused; NumPy bools and 0/1 are flags."""
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber())
    for bad in ("no", "False", 2, 0.5, None):
        with pytest.raises(ValueError, match="must be True or False"):
            p.dynamic = bad
        assert p.dynamic
    p.dynamic = np.bool_(False)
    assert not p.dynamic
    p.dynamic = 1
    assert p.dynamic
