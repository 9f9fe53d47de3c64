"""Regions of a mesh: gmsh physical groups and medit references read by
loadMesh into Mesh.regions (kept through node dropping and splitting),
splitMesh(mesh, by='region'), and a bimaterial bar built from two regions,
whose static stiffness under a slow axial load is the analytic one of two bars
and their contact interface in series."""
import numpy as np
import pytest

import qdem
from qdem.io import cad


def _twoBlocksMsh(path, physical=True):
    """Two 40 x 20 x 20 mm and 20 x 20 x 20 mm blocks sharing a face, meshed
    by gmsh (conformal), in groups 7 and 9, written as .msh (in metres)."""
    gmsh = pytest.importorskip("gmsh")
    with cad._quietFds():
        gmsh.initialize([], False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            occ = gmsh.model.occ
            a = occ.addBox(0, 0, 0, 0.04, 0.02, 0.02)
            b = occ.addBox(0.04, 0, 0, 0.02, 0.02, 0.02)
            out, _ = occ.fragment([(3, a)], [(3, b)])
            occ.synchronize()
            vols = sorted(t for d, t in out if d == 3)
            left = [t for t in vols if occ.getCenterOfMass(3, t)[0] < 0.04]
            right = [t for t in vols if t not in left]
            if physical:
                gmsh.model.addPhysicalGroup(3, left, 7)
                gmsh.model.addPhysicalGroup(3, right, 9)
                gmsh.model.addPhysicalGroup(0, [1], 3)  # a point group: written as a vertex cell
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.006)
            gmsh.model.mesh.generate(3)
            gmsh.write(str(path))
        finally:
            gmsh.finalize()
    return str(path)


def test_gmsh_physical_groups_become_regions(tmp_path):
    path = _twoBlocksMsh(tmp_path / "two.msh")
    mesh = qdem.loadMesh(path)
    assert mesh.regions is not None and sorted(set(mesh.regions)) == [7, 9]
    parts = qdem.splitMesh(mesh, by="region")
    assert list(parts) == [7, 9]
    assert parts[7].volumes().sum() == pytest.approx(0.04 * 0.02 * 0.02, rel=1e-9)
    assert parts[9].volumes().sum() == pytest.approx(0.02 * 0.02 * 0.02, rel=1e-9)
    # each region mesh keeps the file's point indices: its nodes are those points
    import meshio
    pts = meshio.read(path).points
    for sub in parts.values():
        assert np.array_equal(sub.nodes, pts[sub.nodeIds])
        assert np.all(sub.regions == sub.regions[0])
    # the regions share the interface nodes: one connected part
    assert len(qdem.splitMesh(mesh)) == 1
    assert len(np.intersect1d(parts[7].nodeIds, parts[9].nodeIds)) > 0


def test_gmsh_without_physical_groups_has_no_regions(tmp_path):
    mesh = qdem.loadMesh(_twoBlocksMsh(tmp_path / "plain.msh", physical=False))
    assert mesh.regions is None
    with pytest.raises(ValueError, match=r"no regions.*physical groups.*medit references"):
        qdem.splitMesh(mesh, by="region")


def test_medit_references_become_regions_through_dropped_points(tmp_path):
    """A medit file written by meshio with a point no tet uses (dropped) and
    references per tet; regions and nodes follow the same renumbering."""
    import meshio
    m = qdem.boxMesh((0.2, 0.1, 0.1), (4, 2, 2))
    ref = np.where(m.nodes[m.tets].mean(axis=1)[:, 0] < 0, 1, 2)
    pts = np.vstack([[[9.0, 9.0, 9.0]], m.nodes])
    path = str(tmp_path / "bar.mesh")
    meshio.write(path, meshio.Mesh(pts, [("tetra", m.tets + 1)], cell_data={"medit:ref": [ref]}))
    mesh = qdem.loadMesh(path)
    assert mesh.nNodes == m.nNodes and np.array_equal(mesh.regions, ref)
    left = qdem.splitMesh(mesh, by="region")[1]
    assert np.all(left.nodes[:, 0] <= 1e-12)
    assert left.nTets == (ref == 1).sum()
    # kept by scaled() and by the split into connected parts
    assert np.array_equal(mesh.scaled(2.0).regions, ref)
    assert np.array_equal(qdem.splitMesh(mesh)[0].regions, ref)


def test_region_arguments_are_checked():
    m = qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1))
    with pytest.raises(ValueError, match=r"regions must be one integer label per tetrahedron \(6\)"):
        qdem.Mesh(m.nodes, m.tets, regions=[1, 2])
    with pytest.raises(ValueError, match="regions must be one integer"):
        qdem.Mesh(m.nodes, m.tets, regions=np.full(6, 1.5))
    with pytest.raises(ValueError, match=r"by must be 'part' or 'region'"):
        qdem.splitMesh(m, by="material")


# --- a bimaterial bar: two regions, two pieces, joined by contact ------------------

W, L1, L2 = 0.1, 0.2, 0.2
E1, E2 = 2e7, 5e6
R = 0.01


def _bimaterialBar(O, tmp_path, force):
    """A 0.1 x 0.1 x 0.4 m bar written as a medit file with references 1
    (lower half) and 2 (upper half), split by region into two pieces of
    their own material; the upper one lifted by the contact reach r_1 + r_2
    so that the interface starts touching, unloaded.  Poisson's ratio 0 (the
    same in both) makes the bar's uniaxial state exact on linear tets.  The
    bottom face is held, the top face loaded by ``force`` (N, + pulls) spread
    as a uniform traction."""
    import meshio
    from yade import ForceResetter, NewtonIntegrator
    m = qdem.boxMesh((W, W, L1 + L2), (4, 4, 16))
    ref = np.where(m.nodes[m.tets].mean(axis=1)[:, 2] < -0.5 * (L1 + L2) + L1, 1, 2)
    path = str(tmp_path / "bimaterial.mesh")
    meshio.write(path, meshio.Mesh(m.nodes, [("tetra", m.tets)], cell_data={"medit:ref": [ref]}))
    regions = qdem.splitMesh(qdem.loadMesh(path), by="region")
    mats = {1: qdem.QdemMat(young=E1, poisson=0.0, density=1000.0, radius=R, frictionPiece=0.0),
            2: qdem.QdemMat(young=E2, poisson=0.0, density=1000.0, radius=R, frictionPiece=0.0)}
    for k, mat in mats.items():
        mat.viscosity = qdem.modes.viscosityForDamping(regions[k], mat, 0.7)
    lower = qdem.addPiece(regions[1], mats[1])
    upper = qdem.addPiece(regions[2], mats[2], pos=(0, 0, 2 * R))  # r_1 + r_2 apart: touching
    z = lower.pos[:, 2]
    lower.blocked[z < z.min() + 1e-9] = 7
    x = upper.pos
    tris = upper.surface()["triangles"]
    top = np.all(np.abs(x[tris][:, :, 2] - x[:, 2].max()) < 1e-9, axis=1)
    share = np.zeros(len(x))  # each top node's third of its top triangles' area: a uniform traction
    for t in tris[top]:
        share[t] += np.linalg.norm(np.cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]])) / 6.0
    upper.extForce[:, 2] = force * share / share.sum()
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", threads=1), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    return lower, upper, share > 0


def test_bimaterial_bar_in_compression_has_the_series_stiffness(scene, tmp_path):
    """Static shortening under F = 100 N against the two bars and the
    contact interface in series:
        d = F (L1/(E1 A) + L2/(E2 A) + 1/(kn (W1 + W2))),
    kn = 2 E1 r E2 r / (E1 r + E2 r) the contact law's pair stiffness and
    W1, W2 the summed contact weights of the interface nodes of each side
    (both sides' nodes press on the other's faces: doc/contacts.md §5).
    Measured: within 1 % (0.6 %); the bars alone would be 6 % off."""
    O = scene
    F = 100.0
    lower, upper, top = _bimaterialBar(O, tmp_path, -F)
    z1, z2 = lower.pos[:, 2], upper.pos[:, 2]
    face1 = np.abs(z1 - z1.max()) < 1e-9
    face2 = np.abs(z2 - z2.min()) < 1e-9
    kn = 2 * E1 * R * E2 * R / (E1 * R + E2 * R)
    interface = kn * (lower.contactWeight[face1].sum() + upper.contactWeight[face2].sum())
    bars = F * (L1 / (E1 * W * W) + L2 / (E2 * W * W))
    O.run(int(0.1 / O.dt), True)
    assert np.abs(upper.vel).max() < 1e-5  # static
    d = -(upper.pos[top, 2] - upper.refPos[top, 2]).mean()
    assert d == pytest.approx(bars + F / interface, rel=0.01)
    assert abs(d / bars - 1) > 0.03  # the interface's compliance is part of the answer
    # each bar on its own: the stretch of the lower one alone
    d1 = -(lower.pos[face1, 2] - lower.refPos[face1, 2]).mean()
    assert d1 == pytest.approx(F * L1 / (E1 * W * W), rel=0.01)


def test_bimaterial_bar_from_regions_carries_no_tension(scene, tmp_path):
    """Pieces are joined by contact only: pulled, the interface opens and the
    upper piece leaves (what doc/meshes.md says), where a bonded bar would
    stretch by F (L1/(E1 A) + L2/(E2 A))."""
    O = scene
    lower, upper, top = _bimaterialBar(O, tmp_path, +100.0)
    O.run(int(0.05 / O.dt), True)
    bonded = 100.0 * (L1 / (E1 * W * W) + L2 / (E2 * W * W))
    assert upper.velocity[2] > 0
    assert upper.centroid[2] - upper.refPos[:, 2].mean() > 10 * bonded


def test_a_volume_in_two_physical_groups_is_named(tmp_path):
    """MSH 2 writes an element once per physical group: every tet twice.
    Before: 'non-manifold: face ... is shared by 4 tetrahedra'."""
    import meshio
    m = qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2))
    tets = np.vstack([m.tets, m.tets])
    path = str(tmp_path / "twice.msh")
    phys = np.r_[np.full(m.nTets, 1), np.full(m.nTets, 2)]
    meshio.write(path, meshio.Mesh(m.nodes, [("tetra", tets)],
                                   cell_data={"gmsh:physical": [phys], "gmsh:geometrical": [phys]}),
                 file_format="gmsh22", binary=False)
    with pytest.raises(ValueError, match=r"lists 48 tetrahedra more than once .*regions 1, 2.*one physical group"):
        qdem.loadMesh(path)


@pytest.mark.parametrize("binary", [0, 1])
def test_an_msh4_volume_in_two_physical_groups_is_named(tmp_path, binary):
    """MSH 4 writes each element once, and meshio labels it with its volume's
    first physical group: the second group silently lost the volume (before:
    regions 1 and 2 over 690 + 701 tets, volume 1 in region 1 only)."""
    gmsh = pytest.importorskip("gmsh")
    path = str(tmp_path / "groups.msh")
    with cad._quietFds():
        gmsh.initialize([], False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            occ = gmsh.model.occ
            out, _ = occ.fragment([(3, occ.addBox(0, 0, 0, 1, 1, 1))], [(3, occ.addBox(1, 0, 0, 1, 1, 1))])
            occ.synchronize()
            a, b = sorted(t for d, t in out if d == 3)
            gmsh.model.addPhysicalGroup(3, [a], 1)
            gmsh.model.addPhysicalGroup(3, [a, b], 2)  # the whole body, and its left half again
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
            gmsh.model.mesh.generate(3)
            gmsh.option.setNumber("Mesh.Binary", binary)
            gmsh.write(path)
        finally:
            gmsh.finalize()
    with pytest.raises(ValueError, match=r"puts volume %d in more than one physical group \(volume %d in groups 1, 2\)"
                       r".*one physical group only" % (a, a)):
        qdem.loadMesh(path, scale=0.1)
    # One group per volume loads.
    good = _twoBlocksMsh(tmp_path / "two.msh")
    assert sorted(set(qdem.loadMesh(good).regions)) == [7, 9]
