"""Soft bodies dropped on a YADE floor end where physics puts them (issue 12).

A soft cube dropped flat or onto a corner, and a CGAL-meshed soft ball, must
come to rest with no inverted element, no elastic energy locked in beyond the
static sag under their own weight, the floor carrying the weight (1 %) with no
tangential load (1 %); a well-damped cube dropped flat must land flat and stay
where it fell, whatever the tetrahedral split of its cells; a block squeezed
to half its height and released must return to its volume.  Each scene runs
through QdemEngine in YADE, as a user runs it."""
import math

import numpy as np
import pytest

import qdem
import qdem.modes

L = 0.4          # cube side [m]
RHO = 1000.0
G = 9.81


def _scene(O, piece_args, dampingRatio, **engineKw):
    from yade import ForceResetter, NewtonIntegrator, utils
    mesh, mat, pos, ori = piece_args
    mat.viscosity = qdem.modes.viscosityForDamping(mesh, mat, dampingRatio)
    piece = qdem.addPiece(mesh, mat, pos=pos, ori=ori)
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1, **engineKw),
                 NewtonIntegrator(gravity=(0, 0, -G))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    O.trackEnergy = True
    return piece, floor


def _inverted(piece):
    x, t = piece.pos, piece.tets
    d = np.einsum("ij,ij->i", np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]), x[t[:, 3]] - x[t[:, 0]])
    return int((d <= 0).sum())


def _rotation(piece):
    """Best-fit rotation of the piece from its reference shape (Kabsch)."""
    X, x = piece.refPos - piece.refPos.mean(0), piece.pos - piece.pos.mean(0)
    U, _, Vt = np.linalg.svd(X.T @ x)
    d = np.sign(np.linalg.det(U @ Vt))
    return (U @ np.diag([1, 1, d]) @ Vt).T


def _tiltFromAFace(piece, ori=None):
    """Angle [deg] between the vertical and the nearest body axis of the (box)
    piece, which was added rotated by `ori` (a 3x3 matrix)."""
    R = _rotation(piece) @ (np.eye(3) if ori is None else ori)
    return math.degrees(math.acos(min(1.0, np.abs(R[2, :]).max())))


def _runUntilRest(O, piece, tEnd, vRest=2e-3):
    O.run(int(tEnd / O.dt), True)
    assert np.abs(piece.vel).max() < vRest, "not at rest after %.2f s" % O.time


def _checkRest(O, piece, floor, mat):
    weight = piece.totalMass * G
    F = O.forces.f(floor)
    assert F[2] == pytest.approx(-weight, rel=0.01)
    assert math.hypot(F[0], F[1]) < 0.01 * weight
    assert _inverted(piece) == 0


def _cube(E, tpc, corner=False, n=4):
    mat = qdem.QdemMat(young=E, poisson=0.3, density=RHO, radius=0.01, restitution=0.3, frictionWall=0.5)
    mesh = qdem.boxMesh((L, L, L), (n, n, n), tetsPerCell=tpc)
    if corner:  # tilted 35 deg about x, then 25 deg about y: one corner lands first, off the centroid's vertical
        Rx = qdem.world.rotationMatrix(((1.0, 0, 0), math.radians(35)))
        Ry = qdem.world.rotationMatrix(((0, 1.0, 0), math.radians(25)))
        ori = Ry @ Rx
        z = 0.5 - (mesh.nodes @ ori.T)[:, 2].min() + mat.radius
    else:
        ori, z = None, 0.5 + L / 2 + mat.radius
    return mesh, mat, (0.0, 0.0, z), ori


def _sagEnergy(E):
    # A free-standing block under its own weight: uniaxial stress rho g (L - z),
    # U = int sigma^2/(2E) dV = rho^2 g^2 A L^3 / (6 E).
    return RHO ** 2 * G ** 2 * L * L * L ** 3 / (6 * E)


@pytest.mark.parametrize("tpc", [5, 6, 12])
@pytest.mark.parametrize("E", [0.5e6, 2e6])
def test_soft_cube_dropped_flat_comes_to_rest_flat(scene, E, tpc):
    O = scene
    piece, floor = _scene(O, _cube(E, tpc), dampingRatio=0.3)
    _runUntilRest(O, piece, 4.0)
    _checkRest(O, piece, floor, piece.material)
    assert _tiltFromAFace(piece) < 1.0
    # No energy locked in: only the static sag (Poisson and friction at the
    # base change it a little: within 30 %).
    assert O.energy["qdemElastic"] < 1.3 * _sagEnergy(E)
    assert O.engines[1].inverted["now"] == 0


@pytest.mark.parametrize("tpc", [5, 6, 12])
def test_soft_cube_landing_on_a_corner_rests_on_a_face(scene, tpc):
    O = scene
    E = 0.5e6
    args = _cube(E, tpc, corner=True)
    piece, floor = _scene(O, args, dampingRatio=0.3)
    _runUntilRest(O, piece, 9.0, vRest=5e-3)  # it tumbles, then rocks on its contact springs
    _checkRest(O, piece, floor, piece.material)
    assert _tiltFromAFace(piece, args[3]) < 1.0
    assert O.energy["qdemElastic"] < 1.3 * _sagEnergy(E)
    rep = O.engines[1].inverted
    assert rep["now"] == 0  # a law that recovers may invert briefly: reported, never kept
    print("corner landing, %d tets per cell: at most %d inverted, for %.3g s" % (tpc, rep["max"], rep["time"]))


@pytest.mark.parametrize("tpc", [5, 6, 12])
def test_well_damped_cube_lands_flat_where_it_fell(scene, tpc):
    O = scene
    piece, floor = _scene(O, _cube(1e6, tpc), dampingRatio=0.25)
    _runUntilRest(O, piece, 3.0)
    c = piece.centroid
    assert math.hypot(c[0], c[1]) < 0.01
    assert _tiltFromAFace(piece) < 1.0
    _checkRest(O, piece, floor, piece.material)


def test_soft_ball_dropped_stays_uninverted_and_the_floor_carries_its_weight(scene):
    """A CGAL-meshed soft ball dropped on the floor: no element inverted at any
    check, mechanical energy never above the start, and over its last second
    the floor carries its weight (time-averaged reaction within 1 %, tangential
    below 1 %).  A polyhedral ball keeps rolling and rocking from facet to facet
    at a few cm/s after the bounces die out (the asymmetric impacts of its
    facets gave it some spin), so it is not asked to stop."""
    from yade import PyRunner
    O = scene
    mat = qdem.QdemMat(young=0.5e6, poisson=0.3, density=RHO, radius=0.008, restitution=0.3)
    mesh = qdem.ballMesh(0.15, 0.075)
    piece, floor = _scene(O, (mesh, mat, (0, 0, 0.1 + 0.15 + 0.008), None), dampingRatio=0.3)
    e0 = piece.totalMass * G * (0.1 + 0.15 + 0.008)
    O.run(int(3.0 / O.dt), True)
    samples = []
    O.engines = O.engines + [PyRunner(command="samples.append(tuple(O.forces.f(%d)))" % floor, iterPeriod=1)]
    import builtins
    builtins.samples = samples
    O.run(int(1.0 / O.dt), True)
    F = np.mean(samples, axis=0)
    weight = piece.totalMass * G
    assert -F[2] == pytest.approx(weight, rel=0.01)
    assert math.hypot(F[0], F[1]) < 0.01 * weight
    e = O.energy
    mech = e["qdemKinetic"] + e["qdemElastic"] + e["qdemContactElastic"] + piece.totalMass * G * piece.centroid[2]
    assert mech < e0
    assert O.engines[1].inverted["max"] == 0 and _inverted(piece) == 0
    assert np.abs(piece.velocity[2]) < 0.01


def test_block_squeezed_to_half_returns_to_its_volume(scene):
    """Rigid platens (the top and bottom faces' nodes driven in z, free to slide
    sideways) squeeze a soft block to 50 % of its height and let it go: no
    element inverts, and it returns to its volume and height (1 %).  Walls could
    not do it: a node's contact spring, 2 E r, carries at most 2 E r^2 before
    the node passes the wall (doc/hard_cases.md)."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    h = 0.2
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=RHO, radius=0.005)
    mesh = qdem.boxMesh((h, h, h), (4, 4, 4))
    mat.viscosity = qdem.modes.viscosityForDamping(mesh, mat, 0.3)
    piece = qdem.addPiece(mesh, mat)
    V0 = piece.volume
    X = piece.refPos
    top, bottom = np.isclose(X[:, 2], h / 2), np.isclose(X[:, 2], -h / 2)
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1),
                 NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    speed = 0.1  # m/s, 5 % of the shear wave speed: quasi-static
    piece.blocked[top | bottom] = 4
    piece.vel[top, 2], piece.vel[bottom, 2] = -speed / 2, speed / 2
    O.run(int(0.5 * h / speed / O.dt), True)            # to half height
    assert np.ptp(piece.pos[:, 2]) == pytest.approx(0.5 * h, rel=0.02)
    assert _inverted(piece) == 0 and O.engines[1].inverted["max"] == 0
    piece.blocked[:] = 0                                 # let go
    O.run(int(1.0 / O.dt), True)
    x, t = piece.pos, piece.tets
    vol = np.einsum("ij,ij->i", np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]),
                    x[t[:, 3]] - x[t[:, 0]]).sum() / 6
    assert vol == pytest.approx(V0, rel=0.01)
    assert np.ptp(x[:, 2]) == pytest.approx(h, rel=0.01)
    assert _inverted(piece) == 0
