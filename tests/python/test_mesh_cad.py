"""CAD parts meshed by qdem.meshCad (gmsh + OpenCASCADE): STEP files written
here in millimetres come out in metres with the analytic volume, BREP needs
its unit, several solids become regions of one conformal mesh, gmsh leaves
no state or console output behind, bad files are named, and a meshed part
dropped on a YADE floor comes to rest on its contact particles."""
import math
import os
import signal

import numpy as np
import pytest

import qdem
from qdem.io import cad

gmsh = pytest.importorskip("gmsh")

# The part: a 100 x 50 x 20 mm plate with a 10 mm radius hole through it.
PLATE = (100.0, 50.0, 20.0)
HOLE_R = 10.0
PLATE_VOLUME_M3 = (PLATE[0] * PLATE[1] * PLATE[2] - math.pi * HOLE_R**2 * PLATE[2]) * 1e-9


def _writeCad(path, build):
    """Write the shapes made by build(occ) with gmsh's OCC kernel (coordinates
    in mm; gmsh writes STEP in millimetres), quietly, and finalize gmsh."""
    with cad._quietFds():
        gmsh.initialize([], False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.model.add("writer")
            build(gmsh.model.occ)
            gmsh.model.occ.synchronize()
            gmsh.write(str(path))
        finally:
            gmsh.finalize()
    return str(path)


def _plate(occ):
    box = occ.addBox(0, 0, 0, *PLATE)
    hole = occ.addCylinder(PLATE[0] / 2, PLATE[1] / 2, -1, 0, 0, PLATE[2] + 2, HOLE_R)
    occ.cut([(3, box)], [(3, hole)])


@pytest.fixture(scope="module")
def plateStep(tmp_path_factory):
    return _writeCad(tmp_path_factory.mktemp("cad") / "plate_mm.step", _plate)


def test_step_in_millimetres_meshes_in_metres_with_its_volume(plateStep, capfd):
    """The STEP file says millimetres: the mesh is in metres (100 x 50 x 20 mm
    -> 0.1 x 0.05 x 0.02 m), its volume within 1 % of the plate's analytic
    one, linear tets all positive, one region, and nothing printed."""
    capfd.readouterr()
    mesh = qdem.meshCad(plateStep, cellSize=0.005)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    lo, hi = mesh.bounds()
    assert np.allclose(lo, 0, atol=1e-9) and np.allclose(hi, np.array(PLATE) * 1e-3, rtol=1e-6)
    v = mesh.volumes()
    assert v.min() > 0
    assert v.sum() == pytest.approx(PLATE_VOLUME_M3, rel=0.01)
    assert mesh.regions is not None and len(np.unique(mesh.regions)) == 1
    # the cell size is honoured: edges of about the size asked
    e = np.linalg.norm(mesh.nodes[mesh.tets[:, [0, 0, 0, 1, 1, 2]]] - mesh.nodes[mesh.tets[:, [1, 2, 3, 2, 3, 3]]],
                       axis=2)
    assert 0.6 * 0.005 < np.median(e) < 1.1 * 0.005


def test_gmsh_is_left_as_found(plateStep):
    """Twice in a row gives the same mesh; gmsh is finalized afterwards and
    the SIGINT handler (YADE's Ctrl-C) is the one before the call."""
    before = signal.getsignal(signal.SIGINT)
    a = qdem.meshCad(plateStep, cellSize=0.008)
    b = qdem.meshCad(plateStep, cellSize=0.008)
    assert np.array_equal(a.tets, b.tets) and np.array_equal(a.nodes, b.nodes)
    assert signal.getsignal(signal.SIGINT) is before
    assert not cad._gmshIsInitialized(gmsh)


def test_a_gmsh_session_of_the_caller_is_borrowed_and_restored(plateStep):
    """A script that has gmsh open keeps its session, model and options."""
    with cad._quietFds():
        gmsh.initialize([], False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mine")
        gmsh.model.occ.addSphere(0, 0, 0, 1)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
        models = gmsh.model.list()
        mesh = qdem.meshCad(plateStep, cellSize=0.008)
        assert mesh.volumes().sum() == pytest.approx(PLATE_VOLUME_M3, rel=0.02)
        assert gmsh.model.getCurrent() == "mine"
        assert gmsh.model.list() == models
        assert len(gmsh.model.getEntities(3)) == 1
        assert gmsh.option.getNumber("Mesh.MeshSizeMax") == 0.3
        assert gmsh.option.getString("Geometry.OCCTargetUnit") == ""
    finally:
        with cad._quietFds():
            gmsh.finalize()


def test_the_unit_is_read_from_the_step_file(tmp_path, plateStep):
    """The same numbers declared as metres give a part 1000 times larger; a
    STEP file gmsh writes after meshCad is still in millimetres (OpenCASCADE's
    unit setting is process-wide and must be left as found)."""
    with open(plateStep) as f:
        text = f.read()
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    metres = tmp_path / "plate_m.step"
    metres.write_text(text.replace("SI_UNIT(.MILLI.,.METRE.)", "SI_UNIT($,.METRE.)"))
    mesh = qdem.meshCad(str(metres), cellSize=5.0)
    assert mesh.bounds()[1] == pytest.approx(PLATE, rel=1e-6)
    assert mesh.volumes().sum() == pytest.approx(PLATE_VOLUME_M3 * 1e9, rel=0.01)
    again = _writeCad(tmp_path / "again.step", _plate)
    with open(again) as f:
        assert "SI_UNIT(.MILLI.,.METRE.)" in f.read()


def test_brep_needs_its_unit(tmp_path):
    """BREP stores bare numbers: refused without scale, the STEP's mesh with it."""
    path = _writeCad(tmp_path / "plate.brep", _plate)
    with pytest.raises(ValueError, match=r"BREP.*without a length unit.*scale=0\.001"):
        qdem.meshCad(path, cellSize=0.005)
    mesh = qdem.meshCad(path, cellSize=0.005, scale=0.001)
    assert mesh.volumes().sum() == pytest.approx(PLATE_VOLUME_M3, rel=0.01)
    assert mesh.bounds()[1] == pytest.approx(np.array(PLATE) * 1e-3, rel=1e-6)


def test_touching_solids_are_one_conformal_mesh_with_regions(tmp_path):
    """Two blocks sharing a face (a bimaterial part drawn as two solids): one
    connected mesh (nodes shared on the interface), two regions, each region
    the volume of its block."""
    def build(occ):
        occ.addBox(0, 0, 0, 40, 20, 20)
        occ.addBox(40, 0, 0, 20, 20, 20)
    path = _writeCad(tmp_path / "two.step", build)
    mesh = qdem.meshCad(path, cellSize=0.006)
    assert len(qdem.splitMesh(mesh)) == 1
    parts = qdem.splitMesh(mesh, by="region")
    assert len(parts) == 2
    vols = sorted(p.volumes().sum() for p in parts.values())
    assert vols == pytest.approx([8e-6, 16e-6], rel=1e-9)  # flat faces: exact


def test_coarse_chords_on_a_curved_part_are_warned_about(tmp_path):
    """A cylinder meshed with curvature off and a cell as large as its radius
    keeps far less than its volume: the warning says so and names the fix."""
    path = _writeCad(tmp_path / "rod.step", lambda occ: occ.addCylinder(0, 0, 0, 0, 0, 40, 10))
    with pytest.warns(UserWarning, match=r"curved faces are cut by too few chords.*Raise curvature"):
        qdem.meshCad(path, cellSize=0.012, curvature=0)
    mesh = qdem.meshCad(path, cellSize=0.004)  # default curvature: 24 chords a turn
    assert mesh.volumes().sum() == pytest.approx(math.pi * 1e-4 * 0.04, rel=0.015)


def test_bad_files_are_named(tmp_path, plateStep):
    with pytest.raises(ValueError, match="no such file"):
        qdem.meshCad(str(tmp_path / "missing.step"), 0.01)
    junk = tmp_path / "junk.step"
    junk.write_text("this is not a STEP file\n")
    with pytest.raises(ValueError, match=r"cannot read .*junk\.step as STEP|holds no solid"):
        qdem.meshCad(str(junk), 0.01)
    with pytest.raises(ValueError, match=r"not a CAD file.*use qdem\.loadMesh"):
        qdem.meshCad(str(tmp_path / "part.msh"), 0.01)
    with pytest.raises(ValueError, match=r"not a CAD file.*use qdem\.meshSurface"):
        qdem.meshCad(str(tmp_path / "part.stl"), 0.01)
    sheet = _writeCad(tmp_path / "sheet.step", lambda occ: occ.addRectangle(0, 0, 0, 10, 10))
    with pytest.raises(ValueError, match=r"holds no solid \(1 face.*qdem\.meshSurface"):
        qdem.meshCad(sheet, 0.002)
    with pytest.raises(ValueError, match="cellSize must be a finite number > 0"):
        qdem.meshCad(plateStep, 0)
    with pytest.raises(ValueError, match=r"about .* tetrahedra .*check the unit"):
        qdem.meshCad(plateStep, 1e-6)
    assert not cad._gmshIsInitialized(gmsh)  # also after the errors


def test_missing_gmsh_names_the_package(monkeypatch, plateStep):
    import builtins
    real = builtins.__import__

    def noGmsh(name, *a, **kw):
        if name == "gmsh":
            raise ImportError("No module named 'gmsh'")
        return real(name, *a, **kw)
    monkeypatch.setattr(builtins, "__import__", noGmsh)
    with pytest.raises(RuntimeError, match=r"apt-get install python3-gmsh"):
        qdem.meshCad(plateStep, 0.01)


def test_a_step_part_drops_onto_a_floor_and_rests_on_its_particles(scene, plateStep):
    """The plate (mm in the file) meshed, dropped flat from 2 mm onto a YADE
    wall: it comes to rest with its lowest nodes one contact radius above the
    floor less the static sag of the contacts (weight / (n E r)), the floor
    carrying its weight; its mass is rho times the analytic volume."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mesh = qdem.meshCad(plateStep, cellSize=0.012)
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1200.0, radius=0.002, restitution=0.3, frictionWall=0.5)
    mat.viscosity = qdem.modes.viscosityForDamping(mesh, mat, 0.3)
    piece = qdem.addPiece(mesh, mat, pos=(0, 0, 0.002 + mat.radius))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1,
                                                 viscousIntegration="implicit"),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    assert piece.totalMass == pytest.approx(1200.0 * PLATE_VOLUME_M3, rel=0.01)
    O.run(int(0.1 / O.dt), True)
    assert np.abs(piece.vel).max() < 5e-3
    weight = piece.totalMass * 9.81
    assert O.forces.f(floor)[2] == pytest.approx(-weight, rel=0.01)
    z = piece.pos[:, 2]
    bottom = z < z.min() + 1e-4
    sag = weight / (bottom.sum() * mat.young * mat.radius)  # upper bound: the bottom nodes share the weight
    assert mat.radius - 1.5 * sag < z.min() < mat.radius
    assert z.max() - z.min() == pytest.approx(0.02, rel=0.01)  # the plate's own thickness, nearly unloaded
