"""A mesh in millimetres is named as such, with the fix (doc/meshes.md, "What
the checks say").  A part drawn in mm and placed in metres is a body a
thousand times too large: addPiece says so when its size against its
material's contact radius (or against the other bodies) leaves no doubt, and
the refusal of its placement (it starts deep inside the floor) says so first.
Following the advice (scale=0.001) gives a piece that drops onto a floor and
rests; a 30 m boulder is not taken for millimetres."""
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import qdem
import qdem.modes

G = 9.81


def _mat(radius=0.004):
    return qdem.QdemMat(young=2e5, poisson=0.3, density=1100.0, viscosity=0.0, radius=radius, restitution=0.3)


def _unitsWarnings(record):
    return [str(w.message) for w in record if "millimetres" in str(w.message)]


def _floorScene(O):
    from yade import ForceResetter, NewtonIntegrator, utils
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1, viscousIntegration="implicit"),
                 NewtonIntegrator(gravity=(0, 0, -G))]
    return floor


def test_a_box_mesh_in_millimetres_is_named_at_addPiece_and_at_the_refusal(scene):
    O = scene
    mesh = qdem.boxMesh((120.0, 80.0, 40.0), (6, 4, 2))  # a 120 x 80 x 40 mm block, written in mm
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(mesh, _mat(), pos=(0, 0, 0.1))  # placed 10 cm above the floor, in metres
    msgs = _unitsWarnings(rec)
    assert len(msgs) == 1
    assert "looks like millimetres (120-unit coordinates" in msgs[0]
    assert "contact radius of 0.004 m" in msgs[0] and "scale=0.001" in msgs[0] and "0.12 m body" in msgs[0]
    _floorScene(O)
    O.dt = 1e-6
    with pytest.raises(ValueError, match=r"(?s)^piece 0: the mesh looks like millimetres \(120-unit.*"
                                         r"qdem.loadMesh\(path, scale=0.001\).*starts inside obstacle body 0.*"
                                         r"start it at least [\d.]+ m higher"):
        O.engines[1].stepOnce()


def _mmBlock(tmp_path):
    """A 120 x 80 x 40 mm block, its surface written in mm and meshed by
    TetGen with quality on (elements up to 20000 mm^3)."""
    if shutil.which("tetgen") is None:
        pytest.skip("TetGen is not installed (Debian: apt install tetgen)")
    v = np.array([(x, y, z) for x in (-60, 60) for y in (-40, 40) for z in (-20, 20)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    off = tmp_path / "block_mm.off"
    with open(off, "w") as o:
        o.write("OFF\n%d %d 0\n" % (len(v), 2 * len(quads)))
        o.writelines("%.17g %.17g %.17g\n" % tuple(p) for p in v)
        for a, b, c, d in quads:
            o.write("3 %d %d %d\n3 %d %d %d\n" % (a, b, c, a, c, d))
    subprocess.run(["tetgen", "-pqQa20000", str(off)], check=True, capture_output=True)
    return str(tmp_path / "block_mm.1.ele")


def test_a_tetgen_block_in_millimetres_is_named_and_following_the_advice_it_rests_on_a_floor(scene, tmp_path):
    O = scene
    path = _mmBlock(tmp_path)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(qdem.loadMesh(path), _mat(), pos=(0, 0, 0.2))
    msgs = _unitsWarnings(rec)
    assert len(msgs) == 1 and "qdem.loadMesh(path, scale=0.001)" in msgs[0]
    # The advice, followed.
    O.reset()
    qdem.reset()
    mat = _mat()
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        mesh = qdem.loadMesh(path, scale=0.001)
        mat.viscosity = qdem.modes.viscosityForDamping(mesh, mat, 0.3)
        piece = qdem.addPiece(mesh, mat, pos=(0, 0, 0.02 + 0.004 + 0.02))  # 2 cm above the floor
    assert _unitsWarnings(rec) == []
    floor = _floorScene(O)
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    O.run(int(1.0 / O.dt), True)
    assert np.abs(piece.vel).max() < 5e-3
    F = O.forces.f(floor)
    assert F[2] == pytest.approx(-piece.totalMass * G, rel=0.02)
    assert piece.pos[:, 2].min() > 0  # on the floor, not through it
    assert piece.totalMass == pytest.approx(1100 * 0.12 * 0.08 * 0.04, rel=1e-9)  # in metres now


@pytest.mark.parametrize("radius", [0.5, 0.04])
def test_a_30_m_boulder_is_not_taken_for_millimetres(scene, radius):
    """A 30 m block of 3 m cells, contact radius 0.5 m (or the default 0.04 m:
    elements 75x the radius, below the 200x that names millimetres)."""
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(qdem.boxMesh((30.0, 20.0, 15.0), (10, 7, 5)), _mat(radius), pos=(0, 0, 8))
    assert _unitsWarnings(rec) == []


def test_a_millimetre_part_beside_metre_pieces_and_spheres_is_named(scene):
    """Contact radius sized to the mm part (no radius clue): the scene's
    other pieces and YADE spheres, 1000x smaller than it, name the units."""
    from yade import utils
    O = scene
    for k in range(20):
        O.bodies.append(utils.sphere((k, 5, 1), 0.01))
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), _mat(), pos=(5, 5, 1))
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        qdem.addPiece(qdem.boxMesh((100.0, 100.0, 100.0), (4, 4, 4)), _mat(radius=5.0), pos=(0, 0, 60))
    msgs = _unitsWarnings(rec)
    assert len(msgs) == 1 and "beside pieces of 0.1 m" in msgs[0] and "beside spheres of radius 0.01 m" in msgs[0]
