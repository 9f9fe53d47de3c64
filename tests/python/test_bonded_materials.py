"""A bonded piece of several materials (addPiece's regionMaterials): each
element takes the material of its region, in one piece.  Checked against the
analytic answers: two bars in series (compliances add), two layers in
parallel (stiffnesses add), the mass of the two densities, the stable step of
the stiffer and lighter material; a gmsh part of two physical volumes dropped
on a floor keeps its energy ledger; a piece of one material is unchanged."""
import warnings

import numpy as np
import pytest

import qdem
from qdem.io import cad

W, L1, L2 = 0.1, 0.2, 0.2
E1, E2 = 2e7, 5e6
R = 0.01


def _mat(young, density=1000.0, **kw):
    return qdem.QdemMat(young=young, poisson=0.0, density=density, radius=R, frictionPiece=0.0, **kw)


def _twoRegionBox(size, cells, axis, cut):
    """A boxMesh whose elements with centroid coordinate `axis` below `cut` are
    region 1, the others region 2."""
    m = qdem.boxMesh(size, cells)
    c = m.nodes[m.tets].mean(axis=1)[:, axis]
    return qdem.Mesh(m.nodes, m.tets, regions=np.where(c < cut, 1, 2))


def _damped(mesh, mats, ratio=0.7):
    """Each region's viscosity for a damping ratio of the slowest mode of the
    whole mesh in that material (quasi-static loading settles in a few periods)."""
    for m in mats.values():
        m.viscosity = qdem.modes.viscosityForDamping(mesh, m, ratio)
    return mats


def _topFaceShares(piece):
    """Each node's third of the top-face triangles' area (a uniform traction)."""
    x = piece.pos
    tris = piece.surface()["triangles"]
    top = np.all(np.abs(x[tris][:, :, 2] - x[:, 2].max()) < 1e-9, axis=1)
    share = np.zeros(len(x))
    for t in tris[top]:
        share[t] += np.linalg.norm(np.cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]])) / 6.0
    return share


def _engines(O):
    from yade import ForceResetter, NewtonIntegrator
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", threads=1), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]


# --- two materials in series: a bar, lower half stiff, upper half soft -----------


def _seriesBar(O, force, mats):
    mesh = _twoRegionBox((W, W, L1 + L2), (4, 4, 16), 2, -0.5 * (L1 + L2) + L1)
    bar = qdem.addPiece(mesh, regionMaterials=_damped(mesh, mats))
    z = bar.pos[:, 2]
    bar.blocked[z < z.min() + 1e-9] = 7
    share = _topFaceShares(bar)
    bar.extForce[:, 2] = force * share / share.sum()
    _engines(O)
    return bar, share > 0


def test_two_materials_in_series_have_the_series_stiffness(scene):
    """A 0.1 x 0.1 x 0.4 m bar, lower half E1 = 2e7 Pa, upper half E2 = 5e6 Pa,
    Poisson's ratio 0 (the uniaxial state is exact on linear tets), held at
    the bottom and pressed by F = 100 N spread over its top face: its static
    shortening is d = F (L1/(E1 A) + L2/(E2 A)), bonded (no contact
    compliance at the interface, which the split pieces of
    test_mesh_regions.py add).  Measured 0.01 %; one material (E1) for both
    halves would give 2.5x less."""
    O = scene
    F = 100.0
    bar, top = _seriesBar(O, -F, {1: _mat(E1), 2: _mat(E2)})
    assert bar.regionMaterials is not None and bar.material.young == E2  # contacts: the softer on the surface
    O.run(int(0.1 / O.dt), True)
    assert np.abs(bar.vel).max() < 1e-5  # static
    d = -(bar.pos[top, 2] - bar.refPos[top, 2]).mean()
    series = F * (L1 / (E1 * W * W) + L2 / (E2 * W * W))
    assert d == pytest.approx(series, rel=0.01)
    # The interface moved by the stiff half's shortening alone.
    z = bar.refPos[:, 2]
    mid = np.abs(z - (z.min() + L1)) < 1e-9
    d1 = -(bar.pos[mid, 2] - bar.refPos[mid, 2]).mean()
    assert d1 == pytest.approx(F * L1 / (E1 * W * W), rel=0.01)
    # Each half carries the same stress F / A (Cauchy zz, per element).
    s = bar.stress()[:, 2]
    assert s == pytest.approx(np.full(len(s), -F / (W * W)), rel=0.01)


def test_the_series_bar_of_one_material_is_not_the_series_answer(scene):
    """The same bar with one material in both regions shortens by F L / (E1 A):
    the figure the two-material bar must not give (what a piece whose elements
    all took the piece's material would do)."""
    O = scene
    F = 100.0
    same = _mat(E1)
    bar, top = _seriesBar(O, -F, {1: same, 2: same})
    assert bar.regionMaterials is None  # one material: an ordinary piece
    O.run(int(0.1 / O.dt), True)
    d = -(bar.pos[top, 2] - bar.refPos[top, 2]).mean()
    assert d == pytest.approx(F * (L1 + L2) / (E1 * W * W), rel=0.01)
    assert d < 0.5 * F * (L1 / (E1 * W * W) + L2 / (E2 * W * W))


# --- two materials in parallel: a block of two layers side by side ---------------


def test_two_layers_in_parallel_have_the_summed_stiffness(scene):
    """A 0.1 x 0.1 x 0.2 m block, the half x < 0 of E1, the other of E2
    (Poisson 0), its bottom held and its top face moved down by d and held
    there: at rest the reaction is F = (E1 A1 + E2 A2) d / L (both layers
    strained alike; E_eff = (E1 A1 + E2 A2)/A).  Measured from the element
    forces on the held top nodes: within 1 % (0.04 %); E1 alone would be 1.6x off."""
    O = scene
    L, d = 0.2, 1e-3
    mesh = _twoRegionBox((W, W, L), (4, 4, 8), 0, 0.0)
    block = qdem.addPiece(mesh, regionMaterials=_damped(mesh, {1: _mat(E1), 2: _mat(E2)}))
    z = block.refPos[:, 2]
    bottom, top = z < z.min() + 1e-9, z > z.max() - 1e-9
    block.blocked[bottom | top] = 7
    block.pos[top, 2] -= d
    _engines(O)
    O.run(int(0.1 / O.dt), True)
    assert np.abs(block.vel).max() < 1e-6
    F = block.force[top, 2].sum()  # the element forces on the held top nodes push back up
    A1 = A2 = 0.5 * W * W
    assert F == pytest.approx((E1 * A1 + E2 * A2) * d / L, rel=0.01)
    strain = (block.pos[:, 2] - block.refPos[:, 2]) / (z - z.min() + 1e-300)
    inner = ~bottom
    assert strain[inner] == pytest.approx(np.full(inner.sum(), -d / L), rel=0.01)  # uniform in both layers


# --- mass and stable step ----------------------------------------------------------


def test_mass_is_each_element_of_its_own_density(scene):
    """Node masses are the sum of rho_e V_e / 4 over each node's elements, the
    piece's mass rho1 V1 + rho2 V2 (to rounding)."""
    mesh = _twoRegionBox((0.1, 0.1, 0.3), (2, 2, 6), 2, 0.05)
    mats = {1: _mat(E1, density=7800.0), 2: _mat(E2, density=900.0)}
    p = qdem.addPiece(mesh, regionMaterials=mats)
    V = mesh.volumes()
    V1, V2 = V[mesh.regions == 1].sum(), V[mesh.regions == 2].sum()
    assert p.totalMass == pytest.approx(7800.0 * V1 + 900.0 * V2, rel=1e-12)
    rho = np.array([m.density for m in p.tetMaterial])
    vol = p.world.core.tetVolume[p.tetSlice]
    m = np.zeros(len(p.pos))
    np.add.at(m, p.tets.ravel(), np.repeat(rho * vol / 4, 4))
    assert np.asarray(p.mass) == pytest.approx(m, rel=1e-12)
    assert [m.density for m in p.tetMaterial].count(7800.0) == np.count_nonzero(mesh.regions == 1)


def test_stable_step_is_set_by_the_stiffer_lighter_material(scene):
    """The elastic step of a bonded piece is the one of its stiffest
    elements in their own material: a piece of the stiff, light material alone
    on the same mesh has the same; the soft, heavy one alone a 10x larger one.
    The elements named are all of the stiff region; with viscosity the step
    is at most either material's alone (the stiffest frequency with the
    largest damping rate)."""
    mesh = _twoRegionBox((0.1, 0.1, 0.2), (2, 2, 4), 2, 0.0)
    stiff = _mat(1e8, density=500.0, viscosity=50.0)
    soft = _mat(1e7, density=5000.0, viscosity=200.0)
    w = qdem.World()
    with warnings.catch_warnings():
        # No sliver warning: the median element is taken in the stiffest
        # element's material (across materials it was the soft one's: "worst
        # elements cut its stable step 10 x below what its median element allows").
        warnings.simplefilter("error")
        w.addPiece(mesh, regionMaterials={1: stiff, 2: soft})
    s = w.stableDt()
    assert s["medianFactorElastic"] == pytest.approx(1.0, rel=1e-9)
    alone = {}
    for name, m in (("stiff", stiff), ("soft", soft)):
        wa = qdem.World()
        wa.addPiece(mesh, m)
        alone[name] = wa.stableDt()
    assert s["elastic"] == pytest.approx(alone["stiff"]["elastic"], rel=1e-12)
    assert alone["soft"]["elastic"] == pytest.approx(10 * alone["stiff"]["elastic"], rel=1e-9)
    assert len(s["elements"]) > 0 and np.all(mesh.regions[s["elements"]] == 1)
    assert s["viscous"] <= min(alone["stiff"]["viscous"], alone["soft"]["viscous"]) * (1 + 1e-12)


def test_a_bonded_piece_at_its_stable_step_stays_bounded(scene):
    """Run at 0.95 of the reported step with the soft region's large viscosity:
    a free bar struck on one end stays finite and loses energy."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    mesh = _twoRegionBox((0.05, 0.05, 0.2), (2, 2, 8), 2, 0.0)
    p = qdem.addPiece(mesh, regionMaterials={1: _mat(1e8, density=500.0, viscosity=50.0),
                                              2: _mat(1e7, density=5000.0, viscosity=2000.0)})
    p.vel[p.refPos[:, 2] < -0.099, 2] = 1.0
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", threads=1), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.95 * O.engines[1].stableDt()["combined"]
    e0 = 0.5 * (np.asarray(p.mass) * np.asarray(p.vel[:, 2]) ** 2).sum()
    O.run(4000, True)
    assert np.all(np.isfinite(p.pos))
    assert 0.5 * (np.asarray(p.mass)[:, None] * np.asarray(p.vel) ** 2).sum() < e0


# --- one material: unchanged ---------------------------------------------------------


def _shake(w, viaTetMaterial):
    """A viscoelastic block set vibrating by a random velocity field, stepped
    by the core alone: with the core's per-element material list given (all
    one material) or not."""
    m = qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3))
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0, viscosity=5.0, radius=0.01)
    i = w.materialIndex(mat)
    nodes, tets, _, _ = qdem._core.hilbertReorder(m.nodes, m.tets, tetOrder=True)
    w.core.addPiece(nodes, tets, i, [], [i] * len(tets) if viaTetMaterial else [])
    w.core.vel[:] = 0.1 * np.random.default_rng(0).standard_normal(w.core.vel.shape)
    w.core.step(2e-5, 2000)
    return np.array(w.core.pos), np.array(w.core.vel)


def test_one_material_piece_is_bit_identical_through_the_per_element_path(scene):
    """A piece given its per-element materials (all the same) steps exactly as
    the same piece given its material alone: same blocks, same sums."""
    a = _shake(qdem.World(), False)
    b = _shake(qdem.World(), True)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert np.abs(a[1]).max() > 0  # it moved


# --- a gmsh part of two physical volumes, dropped on a floor ---------------------


def _capAndBaseMsh(path):
    """A 40 x 40 x 30 mm block (physical volume 1) under a 40 x 40 x 10 mm cap
    (physical volume 2) sharing its top face, meshed conformally by gmsh."""
    gmsh = pytest.importorskip("gmsh")
    with cad._quietFds():
        gmsh.initialize([], False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            occ = gmsh.model.occ
            a = occ.addBox(0, 0, 0, 0.04, 0.04, 0.03)
            b = occ.addBox(0, 0, 0.03, 0.04, 0.04, 0.01)
            out, _ = occ.fragment([(3, a)], [(3, b)])
            occ.synchronize()
            vols = sorted(t for d, t in out if d == 3)
            base = [t for t in vols if occ.getCenterOfMass(3, t)[2] < 0.03]
            gmsh.model.addPhysicalGroup(3, base, 1)
            gmsh.model.addPhysicalGroup(3, [t for t in vols if t not in base], 2)
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.01)
            gmsh.model.mesh.generate(3)
            gmsh.write(str(path))
        finally:
            gmsh.finalize()
    return str(path)


def test_gmsh_bimaterial_part_dropped_on_a_floor_keeps_its_energy_ledger(scene, tmp_path):
    """The part read with its two physical volumes as regions, added whole
    (no split), dropped tumbling on a floor: O.energy sums to zero within 1 %
    of the gravity work, and it comes to rest on the floor, not through it."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mesh = qdem.loadMesh(_capAndBaseMsh(tmp_path / "capped.msh"))
    assert sorted(set(mesh.regions)) == [1, 2]
    mesh = qdem.Mesh(mesh.nodes - mesh.nodes.mean(axis=0), mesh.tets, regions=mesh.regions)  # turned about its middle
    base = qdem.QdemMat(young=5e6, poisson=0.3, density=2000.0, viscosity=10.0, radius=0.003)
    cap = qdem.QdemMat(young=5e5, poisson=0.45, density=1000.0, viscosity=5.0, radius=0.003)
    p = qdem.addPiece(mesh, regionMaterials={1: base, 2: cap}, pos=(0, 0, 0.08), ori=((1, 1, 0), 2.5))
    assert p.material is cap and len(qdem.defaultWorld().pieces) == 1
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", threads=1), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.trackEnergy = True
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    worst = 0.0
    for _ in range(20):
        O.run(int(0.01 / O.dt), True)
        total = sum(O.energy[k] for k in qdem.yade.engine.ENERGY_KEYS.values())
        worst = max(worst, abs(total))
    grav = abs(O.energy["qdemGravWork"])
    assert grav > 0 and worst < 0.01 * grav
    assert O.energy["qdemViscDissip"] > 0
    assert np.all(np.isfinite(p.pos)) and p.pos[:, 2].min() > -0.003


# --- save and restore, refusals --------------------------------------------------------


def test_a_bonded_piece_is_saved_and_restored(scene, tmp_path):
    """O.save / O.load rebuild the piece with each element's material: the
    run goes on as it would have."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mesh = _twoRegionBox((0.1, 0.1, 0.1), (2, 2, 2), 2, 0.0)
    qdem.addPiece(mesh, regionMaterials={1: _mat(E1, density=3000.0), 2: _mat(E2)}, pos=(0, 0, 0.1))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", threads=1), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableDt()["combined"]
    O.run(200, True)
    path = str(tmp_path / "bonded.yade")
    O.save(path)
    O.run(300, True)
    ref = np.array(qdem.defaultWorld().pieces[0].pos)
    O.load(path)
    p = qdem.defaultWorld().pieces[0]
    assert sorted(p.regionMaterials) == [1, 2] and p.regionMaterials[1].density == 3000.0
    assert sorted({m.density for m in p.tetMaterial}) == [1000.0, 3000.0]
    O.run(300, True)
    assert np.array_equal(np.array(p.pos), ref)


def test_region_materials_are_checked(scene):
    mesh = _twoRegionBox((0.1, 0.1, 0.1), (1, 1, 2), 2, 0.0)
    with pytest.raises(ValueError, match=r"regions 2 have no material: list them in regionMaterials"):
        qdem.addPiece(mesh, regionMaterials={1: _mat(E1)})
    with pytest.raises(ValueError, match=r"names region 5, which the mesh does not have \(its regions: 1, 2\)"):
        qdem.addPiece(mesh, _mat(E1), regionMaterials={5: _mat(E2)})
    with pytest.raises(ValueError, match=r"share one contact radius.*0.01 m, 0.02 m"):
        qdem.addPiece(mesh, regionMaterials={1: _mat(E1), 2: qdem.QdemMat(radius=0.02)})
    with pytest.raises(ValueError, match=r"targetDt .* not available for a piece of several materials"):
        qdem.addPiece(mesh, regionMaterials={1: _mat(E1), 2: _mat(E2)}, targetDt=1e-5)
    plain = qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1))
    with pytest.raises(ValueError, match=r"the mesh has no regions"):
        qdem.addPiece(plain, regionMaterials={1: _mat(E1)})
    # Nothing was added by the refused calls: the next piece is piece 0.
    assert qdem.addPiece(mesh, regionMaterials={1: _mat(E1), 2: _mat(E2)}).id == 0


def test_a_bonded_piece_split_across_two_ranks_steps_as_serially():
    """Under MPI a bonded bar spanning two ranks steps as one process does (to
    the rounding of the partial force sums): every rank holds each element's
    material, so the element blocks of either material compute alike."""
    from mpi_launch import mpirun, python, requireMpi, result
    requireMpi()
    rc, out = mpirun(2, python("tests/mpi/check_bonded.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert all(n > 0 for n in r["tetsPerRank"])
    assert r["disp"] > 1e-3 and r["viscous"] > 0
    assert r["dx"] <= 1e-12 * r["disp"] + 1e-15
    assert r["dv"] <= 1e-9 * r["vmax"]
