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


def _tiltFromAFace(piece):
    """Angle [deg] between the vertical and the nearest body axis of the (box) piece."""
    R = _rotation(piece)
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
    mat = qdem.QdemMat(young=E, poisson=0.3, density=RHO, radius=0.01, restitution=0.5, frictionWall=0.5)
    mesh = qdem.boxMesh((L, L, L), (n, n, n), tetsPerCell=tpc)
    if corner:  # the body diagonal vertical: one corner down
        ori = ((1.0, -1.0, 0.0), math.atan(math.sqrt(2.0)))
        z = 0.5 + L * math.sqrt(3) / 2 + mat.radius
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
    piece, floor = _scene(O, _cube(E, tpc), dampingRatio=0.1)
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
    piece, floor = _scene(O, _cube(E, tpc, corner=True), dampingRatio=0.1)
    _runUntilRest(O, piece, 5.0)
    _checkRest(O, piece, floor, piece.material)
    assert _tiltFromAFace(piece) < 1.0
    assert O.energy["qdemElastic"] < 1.3 * _sagEnergy(E)
    rep = O.engines[1].inverted
    assert rep["now"] == 0  # a law that recovers may invert briefly: reported, never kept
    print("corner landing, %d tets per cell: at most %d inverted, for %.3g s" % (tpc, rep["max"], rep["time"]))


@pytest.mark.parametrize("tpc", [5, 6, 12])
def test_well_damped_cube_lands_flat_where_it_fell(scene, tpc):
    O = scene
    piece, floor = _scene(O, _cube(1e6, tpc), dampingRatio=0.25)
    _runUntilRest(O, piece, 3.0)
    c = piece.centroid()
    assert math.hypot(c[0], c[1]) < 0.01
    assert _tiltFromAFace(piece) < 1.0
    _checkRest(O, piece, floor, piece.material)


def test_soft_ball_comes_to_rest_uninverted(scene):
    O = scene
    mat = qdem.QdemMat(young=0.5e6, poisson=0.3, density=RHO, radius=0.008, restitution=0.5)
    mesh = qdem.ballMesh(0.15, 0.04)
    piece, floor = _scene(O, (mesh, mat, (0, 0, 0.5 + 0.15 + 0.008), None), dampingRatio=0.1)
    _runUntilRest(O, piece, 4.0)
    _checkRest(O, piece, floor, mat)
    c = piece.centroid()
    assert math.hypot(c[0], c[1]) < 0.01


def test_block_squeezed_to_half_returns_to_its_volume(scene):
    """Two walls squeeze a soft block to 50 % of its height and let it go."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    h = 0.2
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=RHO, radius=0.005, frictionWall=0.0)
    mesh = qdem.boxMesh((h, h, h), (4, 4, 4))
    mat.viscosity = qdem.modes.viscosityForDamping(mesh, mat, 0.2)
    piece = qdem.addPiece(mesh, mat, pos=(0, 0, h / 2 + mat.radius))
    V0 = piece.volume
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    top = O.bodies.append(utils.wall(h + 2 * mat.radius, axis=2, sense=-1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=50, threads=1), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    speed = 0.05 * h / 0.1  # slow against the wave speed (quasi-static)
    O.bodies[top].state.vel = (0, 0, -speed)
    O.run(int(0.5 * h / speed / O.dt), True)           # to half height
    assert np.ptp(piece.pos[:, 2]) < 0.55 * h
    assert _inverted(piece) == 0
    O.bodies[top].state.vel = (0, 0, speed)
    O.run(int(0.5 * h / speed / O.dt), True)           # back: the walls let go
    O.bodies[top].state.vel = (0, 0, 0)
    O.run(int(0.5 / O.dt), True)
    X = piece.pos
    x, t = X, piece.tets
    vol = np.einsum("ij,ij->i", np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]),
                    x[t[:, 3]] - x[t[:, 0]]).sum() / 6
    assert vol == pytest.approx(V0, rel=0.01)
    assert np.ptp(X[:, 2]) == pytest.approx(h, rel=0.01)
    assert _inverted(piece) == 0
