"""Shared helpers of the accuracy study (scripts/accuracy): materials, floor,
timing, sphere surfaces, convergence-order fits.  Each problem module defines
``cases(short)`` -> list of (knob, label, kwargs) and ``run(**kwargs)`` -> dict
with at least ``error`` (signed, relative unless the problem says otherwise),
``wall`` (seconds of stepping), ``steps`` and ``nTets``."""
import math
import time

import numpy as np

import qdem
from qdem import _core

G = 9.81
# The study's material-law knob: QdemMat.law values and their labels.
LAW_LABELS = {"stableNeoHookean": "stable Neo-Hookean", "saintVenantKirchhoff": "Saint-Venant-Kirchhoff"}


def oneThread():
    """The study runs on one thread (shared machine; threads change the cost,
    never the result: tests/python/test_threads.py)."""
    _core.setThreads(1)


def lame(E, nu):
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def floor(world, z=0.0):
    """A fixed one-sided floor wall at height z facing +z (a YADE Wall)."""
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    world.core.setObstacles([o])
    world.core.setObstacleStates(np.array([[0, 0, z, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))


class Stepper:
    """Steps a world and adds up the time spent stepping: wall time, or with
    clock=time.process_time the CPU time (one thread: the wall time on a quiet
    core, and steadier on a shared machine)."""

    def __init__(self, world, dt, clock=time.perf_counter):
        self.world, self.dt, self.wall, self.steps, self.clock = world, dt, 0.0, 0, clock
        self.maxEdgeEdge = 0  # most edge-edge contacts seen at the end of a call

    def __call__(self, n):
        t = self.clock()
        self.world.core.step(self.dt, int(n))
        self.wall += self.clock() - t
        self.steps += int(n)
        self.maxEdgeEdge = max(self.maxEdgeEdge, self.world.core.contactCounts["edgeEdge"])

    @property
    def time(self):
        return self.steps * self.dt


def setOptions(world, regions=True, edgeEdge=True, friction="spring", vReg=1e-3, broadPhase="triangles"):
    c = world.core
    c.pointPolygonRegions = bool(regions)
    c.edgeEdgeOn = bool(edgeEdge)
    c.frictionModel = {"spring": 0, "regularized": 1}[friction]
    c.frictionRegVelocity = float(vReg)
    c.broadPhase = {"triangles": 0, "A": 1, "B": 2, "C": 3}[broadPhase]


def icosphere(R, subdivisions):
    """Closed triangulated sphere of radius R (qdem.shapes.icosphere)."""
    from qdem.shapes import icosphere as _icosphere
    return _icosphere(R, subdivisions)


def fitOrder(h, err):
    """Least-squares slope p of log|err| = p log h + c (the convergence order)."""
    h, err = np.asarray(h, float), np.abs(np.asarray(err, float))
    ok = err > 0
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)[0])


def finite(x):
    return x if (isinstance(x, (int, float)) and math.isfinite(x)) else None
