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
    # are stiff in bending, converging from above (20x2x2: +23 %, 40x4x4: +4.4 %).
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
