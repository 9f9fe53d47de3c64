"""Shared fixtures: every test starts from an empty YADE scene and QDEM world."""
import numpy as np
import pytest

import qdem


@pytest.fixture
def scene():
    """A clean YADE scene (O) with an empty default QDEM world."""
    from yade import O
    O.reset()
    qdem.reset()
    qdem._core.setThreads(2)
    yield O
    O.reset()
    qdem.reset()


def rubber(**kw):
    """A soft test material: fast to integrate, easy numbers."""
    args = dict(young=1e7, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.005, restitution=0.5)
    args.update(kw)
    return qdem.QdemMat(**args)


def lame(mat):
    lam = mat.young * mat.poisson / ((1 + mat.poisson) * (1 - 2 * mat.poisson))
    mu = mat.young / (2 * (1 + mat.poisson))
    return lam, mu


def totalEnergy(e):
    return sum(v for k, v in e.items() if k != "total")


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
