"""Shared fixtures: every test starts from an empty YADE scene and QDEM world.

Run inside YADE (tests/python/run_pytest.py), on one process or on pytest-xdist
workers (`make test-py`: two, one per core).  Each test gets THREADS OpenMP
threads: 2 on one process, 1 on each of several workers (the cores are
theirs), QDEM_TEST_THREADS to choose; the tests of 1 and 2 threads set theirs."""
import os

import numpy as np
import pytest

import qdem

_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
THREADS = int(os.environ.get("QDEM_TEST_THREADS", "1" if _WORKERS > 1 else "2"))


def pytest_collection_modifyitems(config, items):
    """Under xdist (--dist loadgroup) the MPI tests run one after another on one
    worker: each launches up to 4 ranks on the 2 cores already."""
    for item in items:
        if item.path.name == "test_mpi.py":
            item.add_marker(pytest.mark.xdist_group("mpi"))


@pytest.fixture(autouse=True)
def _threads():
    """Every test starts with THREADS threads, whatever the one before it set."""
    qdem._core.setThreads(THREADS)
    yield


@pytest.fixture
def scene():
    """A clean YADE scene (O) with an empty default QDEM world."""
    from yade import O
    O.reset()
    qdem.reset()
    qdem._core.setThreads(THREADS)
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
