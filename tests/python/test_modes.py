"""qdem.modes: natural frequencies of a free piece against beam theory, and
the viscosity that sets a mode's damping ratio (checked in a free decay)."""
import math

import numpy as np
import pytest

import qdem
import qdem.modes as modes


def _bar(cells):
    return qdem.boxMesh((1.0, 0.1, 0.1), cells, tetsPerCell=6)


def test_free_bar_frequencies_match_beam_theory():
    E, nu, rho = 1e6, 0.3, 1000.0
    mat = qdem.QdemMat(young=E, poisson=nu, density=rho, viscosity=0, radius=0.01)
    w = modes.naturalFrequencies(_bar((40, 4, 4)), mat, 8)   # 3,075 DOF: the sparse solver
    # Axial mode of a free-free bar, pi c / L (c = sqrt(E/rho)): present and within 0.5 %.
    axial = math.pi * math.sqrt(E / rho)
    assert np.min(np.abs(w - axial)) / axial < 5e-3
    # First bending pair: Euler-Bernoulli 4.730^2 sqrt(EI/(rho A L^4)); linear tetrahedra
    # are stiff in bending, converging from above as h^2 (6 tets per cell: 20x2x2: +30.9 %,
    # 40x4x4: +7.3 %).
    b = 0.1
    bending = 4.730 ** 2 * math.sqrt(E * b ** 4 / 12 / (rho * b * b))
    assert bending < w[0] < 1.08 * bending
    coarse = modes.naturalFrequencies(_bar((20, 2, 2)), mat, 2)  # dense solver
    assert coarse[0] > w[0]


def test_viscosity_for_damping_gives_the_mode_its_damping_ratio():
    """A free cube started in its first mode decays at xi*omega with the viscosity asked for."""
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0, viscosity=0, radius=0.01)
    mesh = qdem.boxMesh((0.4, 0.4, 0.4), (3, 3, 3), tetsPerCell=6)
    xi = 0.05
    mat.viscosity = modes.viscosityForDamping(mesh, mat, xi)
    assert modes.dampingRatio(mesh, mat) == pytest.approx(xi, rel=1e-12)
    omega = modes.naturalFrequencies(mesh, mat, 1)[0]
    # The mode shape: the lowest non-rigid eigenvector, by the same assembly.
    shape, lumpedMass = modes.modeShape(mesh, mat, omega)
    w = qdem.World()
    p = w.addPiece(mesh, mat, reorder=False)
    p.vel[:] = 1e-3 * shape / np.abs(shape).max()          # small: linear regime
    dt = 0.2 * w.stableDt()["combined"]
    amp = []
    steps = int(6 * 2 * math.pi / omega / dt)
    for _ in range(steps):
        w.core.step(dt, 1)
        amp.append(float(np.sum(p.vel * shape * lumpedMass[:, None])))
    amp = np.abs(np.array(amp))
    # Peak envelope over the 6 periods: ln(first/last peak) = xi * omega * elapsed.
    per = int(2 * math.pi / omega / dt)
    peaks = [amp[i * per // 2:(i + 1) * per // 2].max() for i in range(12)]
    rate = math.log(peaks[1] / peaks[-1]) / ((len(peaks) - 2) * 0.5 * 2 * math.pi / omega)
    assert rate == pytest.approx(xi * omega, rel=0.05)


@pytest.mark.parametrize("size, young, density", [
    (0.01, 2e11, 7800),    # 1 cm steel: omega^2 ~ 1e12
    (0.004, 5e8, 700),     # 4 mm at the seed's modulus
    (0.02, 1e10, 600),     # 2 cm wood
    (30.0, 1e5, 2000),     # a 30 m soft block: omega ~ 1
])
def test_frequencies_scale_as_wave_speed_over_size_whatever_the_units(size, young, density):
    """omega L / c depends on the mesh's shape alone.  The sparse solver (729 nodes,
    2,187 DOF) once used an absolute shift and zero threshold: small stiff pieces got
    rigid modes as elastic ones, a viscosity 1e8 too large, or an IndexError."""
    mesh = qdem.boxMesh((1.0, 1.0, 1.0), (8, 8, 8))
    ref = modes.naturalFrequencies(mesh, qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0), 4)
    refShape = ref / math.sqrt(1e6 / 1000.0)
    mat = qdem.QdemMat(young=young, poisson=0.3, density=density)
    scaled = qdem.Mesh(mesh.nodes * size, mesh.tets)
    w = modes.naturalFrequencies(scaled, mat, 4)
    assert w * size / math.sqrt(young / density) == pytest.approx(refShape, rel=1e-6)
    lam, mu = modes.lame(mat)
    assert modes.viscosityForDamping(scaled, mat, 0.1) == pytest.approx(mu * 0.2 / w[0], rel=1e-6)


def test_two_separate_parts_have_twelve_rigid_modes_and_the_same_elastic_ones():
    cube = qdem.boxMesh((1.0, 1.0, 1.0), (8, 8, 8))
    n = len(cube.nodes)
    two = qdem.Mesh(np.vstack([cube.nodes, cube.nodes + (3.0, 0, 0)]),
                    np.vstack([cube.tets, cube.tets + n]))
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0)
    one = modes.naturalFrequencies(cube, mat, 2)
    both = modes.naturalFrequencies(two, mat, 4)
    assert both == pytest.approx(np.repeat(one, 2), rel=1e-6)


def test_bad_count_or_mode_is_refused():
    mesh = qdem.boxMesh((1.0, 1.0, 1.0), (1, 1, 1))
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0)
    with pytest.raises(ValueError, match="count"):
        modes.naturalFrequencies(mesh, mat, 0)
    with pytest.raises(ValueError, match="mode"):
        modes.viscosityForDamping(mesh, mat, 0.1, mode=-1)
    with pytest.raises(ValueError, match="elastic modes"):
        modes.naturalFrequencies(mesh, mat, 1000)
    with pytest.raises(ValueError, match="dampingRatio"):
        modes.viscosityForDamping(mesh, mat, -0.1)
