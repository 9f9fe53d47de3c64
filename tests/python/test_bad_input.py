"""Bad input gets a clear error naming the problem, never a crash or a silent NaN."""
import numpy as np
import pytest

import qdem


def _tet():
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return nodes, np.array([[0, 1, 2, 3]])


def test_inverted_tet():
    nodes, tets = _tet()
    with pytest.raises(ValueError, match="tetrahedron 0 is inverted"):
        qdem.Mesh(nodes, tets[:, [0, 2, 1, 3]])


def test_zero_volume_tet():
    nodes, tets = _tet()
    nodes[3] = (0.5, 0.5, 0.0)
    with pytest.raises(ValueError, match="zero volume"):
        qdem.Mesh(nodes, tets)
    with pytest.raises(ValueError, match="repeats node"):
        qdem.Mesh(nodes, [[0, 1, 1, 3]])


def test_nan_coordinate():
    nodes, tets = _tet()
    nodes[2, 1] = np.nan
    with pytest.raises(ValueError, match="node 2 has a NaN"):
        qdem.Mesh(nodes, tets)


def test_index_out_of_range_and_bad_shapes():
    nodes, tets = _tet()
    with pytest.raises(ValueError, match="refers to node 7"):
        qdem.Mesh(nodes, [[0, 1, 2, 7]])
    with pytest.raises(ValueError, match="shape"):
        qdem.Mesh(nodes[:, :2], tets)
    with pytest.raises(ValueError, match="integer"):
        qdem.Mesh(nodes, tets.astype(float))


@pytest.mark.parametrize("kw, word", [({"young": 0}, "young"), ({"young": -1e6}, "young"),
                                      ({"poisson": 0.5}, "poisson"), ({"poisson": -1.0}, "poisson"),
                                      ({"density": 0}, "density"), ({"viscosity": -1}, "viscosity"),
                                      ({"young": float("nan")}, "young"), ({"restitution": 0}, "restitution"),
                                      ({"young": float("inf")}, "young"), ({"poisson": float("nan")}, "poisson"),
                                      ({"density": -5}, "density"), ({"density": float("nan")}, "density"),
                                      ({"viscosity": float("nan")}, "viscosity"), ({"radius": 0}, "radius"),
                                      ({"radius": -1e-3}, "radius"), ({"radius": float("nan")}, "radius"),
                                      ({"frictionPiece": -0.1}, "frictionPiece"),
                                      ({"frictionWall": float("nan")}, "frictionWall"),
                                      ({"restitution": 1.5}, "restitution"),
                                      ({"restitution": float("nan")}, "restitution")])
def test_bad_material_parameters(kw, word):
    with pytest.raises(ValueError, match=word):
        qdem.QdemMat(**kw)


def test_unknown_keywords():
    with pytest.raises(TypeError, match="unknown keyword 'youngs'"):
        qdem.QdemMat(youngs=1e6)
    with pytest.raises(TypeError, match="unknown keyword 'gravity'"):
        qdem.QdemEngine(gravity=(0, 0, -9.81))


def test_bad_piece_arguments():
    w = qdem.World()
    with pytest.raises(ValueError, match="material"):
        w.addPiece(qdem.boxMesh(), material="steel")
    with pytest.raises(ValueError, match="rotation"):
        w.addPiece(qdem.boxMesh(), ori=np.ones((3, 3)))
    with pytest.raises(ValueError, match="no such file"):
        w.addPiece("does/not/exist.msh")
    assert w.core.nPieces == 0          # nothing half-added


def test_broken_mesh_files(tmp_path):
    bad = tmp_path / "broken.msh"
    bad.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\ngarbage\n")
    with pytest.raises(ValueError, match="cannot read"):
        qdem.loadMesh(str(bad))
    tri = tmp_path / "flat.vtu"
    import meshio
    meshio.write(str(tri), meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(ValueError, match="no tetrahedra"):
        qdem.loadMesh(str(tri))


def test_nan_state_is_reported_not_propagated():
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(viscosity=0))
    p.vel[3, 0] = np.nan
    with pytest.raises(qdem.StabilityError, match="checkFinite|not finite at node"):
        w.core.checkFinite()
    # The step that meets it stops, naming the node and the likely causes.
    with pytest.raises(qdem.StabilityError, match=r"during step 1 .*node 3 of piece 0 has a velocity that is not "
                                                  r"finite.*NaN was written into the piece's pos or vel"):
        w.core.step(1e-7, 3)
    assert w.core.iter == 0  # the failed step is not counted


@pytest.mark.parametrize("column", ["pos", "extForce"])
def test_a_nan_stops_the_very_step_it_enters(column):
    """No run ends on a NaN it did not report: the integration checks every
    node it moves, every step (QdemEngine's checks run every checkPeriod
    steps, so a short run could end on one)."""
    w = qdem.World()
    a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(viscosity=0))
    b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(viscosity=0), pos=(1, 0, 0))
    w.core.step(1e-6, 5)
    getattr(b, column)[4, 2] = np.inf if column == "extForce" else np.nan
    want = (r"during step 6 .*node 4 of piece 1 .*extForce\[4\] = \(0, 0, inf\).*Set finite external forces"
            if column == "extForce" else r"during step 6 .*node \d+ of piece 1 has a")
    with pytest.raises(qdem.StabilityError, match=want):
        w.core.step(1e-6, 3)
    assert w.core.iter == 5
    assert np.isfinite(a.pos).all()


def test_a_nan_external_force_stops_a_short_yade_run():
    from yade import O, ForceResetter, NewtonIntegrator
    O.reset()
    p = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(viscosity=0), pos=(0, 0, 1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * qe.stableTimeStep()  # noqa: F821 (label)
    O.run(3, True)
    p.extForce[2, 0] = np.nan
    with pytest.raises(qdem.StabilityError, match=r"node 2 of piece 0 .*extForce\[2\]"):
        O.run(20, True)  # shorter than checkPeriod (100)
    O.reset()


def test_mesh_with_unused_node_is_rejected():
    nodes, tets = _tet()
    nodes = np.vstack([nodes, [5, 5, 5]])
    w = qdem.World()
    with pytest.raises(ValueError, match="belongs to no tetrahedron"):
        w.addPiece((nodes, tets), reorder=False)


# --- issue 6, second set ----------------------------------------------------

def _goodFile(tmp_path, ext):
    import meshio
    m = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    kw = {"file_format": "gmsh22", "binary": False} if ext == "msh" else {}
    path = tmp_path / ("good." + ext)
    meshio.write(str(path), meshio.Mesh(np.asarray(m.nodes), [("tetra", np.asarray(m.tets))]), **kw)
    return path


@pytest.mark.parametrize("ext", ["msh", "vtu", "mesh"])
@pytest.mark.parametrize("keep", [0.0, 0.5, 0.9])
def test_truncated_mesh_files(tmp_path, ext, keep):
    """Cut short at 0, 50 and 90 %.  A truncated .vtu used to end YADE itself:
    meshio prints the reason and calls sys.exit(1)."""
    data = _goodFile(tmp_path, ext).read_bytes()
    bad = tmp_path / ("cut." + ext)
    bad.write_bytes(data[:int(keep * len(data))])
    with pytest.raises(ValueError, match="loadMesh: cannot read .*cut." + ext):
        qdem.loadMesh(str(bad))


def test_nan_coordinate_in_a_mesh_file(tmp_path):
    import meshio
    m = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    nodes = np.asarray(m.nodes).copy()
    nodes[3, 1] = np.nan
    path = tmp_path / "nan.vtu"
    meshio.write(str(path), meshio.Mesh(nodes, [("tetra", np.asarray(m.tets))]))
    with pytest.raises(ValueError, match="node 3 has a NaN"):
        qdem.loadMesh(str(path))


def test_tetrahedra_meeting_at_one_node_or_one_edge_are_non_manifold():
    """Two tetrahedra sharing only a node (a pinched vertex: accepted before)
    or only an edge."""
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1.0]])
    with pytest.raises(ValueError, match="non-manifold surface: node 0"):
        qdem.World().addPiece((nodes, [[0, 1, 2, 3], [0, 4, 6, 5]]), reorder=False)
    nodes = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0.0]])
    tets = np.array([[0, 1, 2, 3], [0, 1, 4, 5]])
    tets = np.where(qdem._core.tetVolumes(nodes, tets)[:, None] < 0, tets[:, [0, 2, 1, 3]], tets)
    with pytest.raises(ValueError, match="non-manifold surface: edge"):
        qdem.World().addPiece((nodes, tets), reorder=False)


_CUBE_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1.0]])
_CUBE_F = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
                    [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def _off(path, v, f, keep=1.0):
    text = "OFF\n%d %d 0\n" % (len(v), len(f)) + "".join("%r %r %r\n" % tuple(x) for x in v) + \
        "".join("3 %d %d %d\n" % tuple(x) for x in f)
    path.write_text(text[:int(keep * len(text))])
    return str(path)


def test_broken_and_non_manifold_surfaces(tmp_path):
    """Surfaces for CGAL meshing: truncated and empty OFF files, NaN vertices,
    two cubes sharing an edge, a fin face, bad cell sizes."""
    with pytest.raises(ValueError, match="loadSurface: cannot read"):
        qdem.meshSurface(_off(tmp_path / "cut.off", _CUBE_V, _CUBE_F, keep=0.6), 0.3)
    with pytest.raises(ValueError, match="loadSurface: cannot read"):
        qdem.meshSurface(_off(tmp_path / "empty.off", _CUBE_V, _CUBE_F, keep=0.0), 0.3)
    v = _CUBE_V.copy()
    v[2, 0] = np.nan
    with pytest.raises(ValueError, match="vertex 2 has a NaN"):
        qdem.meshSurface((v, _CUBE_F), 0.3)
    two = np.vstack([_CUBE_V, _CUBE_V + (1, 1, 0)])
    uniq, inv = np.unique(two, axis=0, return_inverse=True)
    with pytest.raises(ValueError, match="not manifold: edge .* belongs to 4 triangles"):
        qdem.meshSurface(_off(tmp_path / "two.off", uniq, inv.ravel()[np.vstack([_CUBE_F, _CUBE_F + 8])]), 0.3)
    with pytest.raises(ValueError, match="not manifold: edge .* belongs to 3 triangles"):
        qdem.meshSurface((_CUBE_V, np.vstack([_CUBE_F, [[0, 6, 2]]])), 0.3)
    for cell in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="cellSize must be finite and > 0"):
            qdem.meshSurface((_CUBE_V, _CUBE_F), cell)


def test_non_finite_initial_velocity_and_time_step():
    w = qdem.World()
    with pytest.raises(ValueError, match="vel=.* is not finite"):
        w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1)), vel=(0, np.nan, 0))
    with pytest.raises(ValueError, match="angVel=.* is not finite"):
        w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1)), angVel=(0, np.inf, 0))
    assert w.core.nPieces == 0
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1)))
    for dt in (float("nan"), -1e-6, 0.0, float("inf")):
        with pytest.raises(qdem.StabilityError, match="positive"):
            w.core.step(dt, 1)
        with pytest.raises(qdem.StabilityError, match="positive"):
            w.core.checkDt(dt)
        with pytest.raises(qdem.StabilityError, match="positive"):
            w.core.checkCurrentDt(dt)


@pytest.mark.parametrize("kw", [dict(density=1e-300), dict(viscosity=1e300), dict(young=1e300)])
def test_materials_at_the_edge_of_the_doubles_get_a_finite_limit_that_refuses_dt(kw):
    """The leapfrog limit 2/w (sqrt(1 + xi^2) - xi) overflowed or cancelled: density
    1e-300 gave a combined limit of inf (any O.dt passed), viscosity 1e300 inf too."""
    args = dict(young=1e6, poisson=0.3, density=1000.0, viscosity=10.0, radius=0.005)
    args.update(kw)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(**args))
    sd = w.stableDt()
    assert 0 <= sd["combined"] < 1e-100
    with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
        w.core.checkDt(1e-6)


@pytest.mark.parametrize("value", [8, 255])
def test_a_blocked_value_outside_the_bit_mask_is_refused(value):
    """Piece.blocked is a bit mask (1 = x, 2 = y, 4 = z): 8, or -1 (255),
    were accepted and meant nothing, so the piece ran unconstrained."""
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat())
    p.blocked[3] = value
    before = w.core.pos.copy()
    with pytest.raises(ValueError, match=r"node 3 of piece 0 has blocked = %d: blocked is a bit mask of the "
                                         r"prescribed DOFs, 1 = x, 2 = y, 4 = z \(0 to 7" % value):
        w.core.step(1e-6, 1)
    assert np.array_equal(w.core.pos, before)
    p.blocked[3] = 7
    w.core.step(1e-6, 1)


def test_contact_weights_are_read_only():
    """A copy computed from the surface: a write would go nowhere."""
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat())
    with pytest.raises(ValueError, match="read-only"):
        p.contactWeight[0] = 2.0
