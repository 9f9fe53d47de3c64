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
    """Steps a world and adds up the wall time spent stepping."""

    def __init__(self, world, dt):
        self.world, self.dt, self.wall, self.steps = world, dt, 0.0, 0
        self.maxEdgeEdge = 0  # most edge-edge contacts seen at the end of a call

    def __call__(self, n):
        t = time.perf_counter()
        self.world.core.step(self.dt, int(n))
        self.wall += time.perf_counter() - t
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
    """Closed triangulated sphere of radius R: the icosahedron, each triangle
    split in four `subdivisions` times, vertices pushed onto the sphere."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(subdivisions):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                x = v[a] + v[b]
                v.append(x / np.linalg.norm(x))
                mid[k] = len(v) - 1
            return mid[k]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return R * np.array(v), np.array(f, dtype=np.int32)


def fitOrder(h, err):
    """Least-squares slope p of log|err| = p log h + c (the convergence order)."""
    h, err = np.asarray(h, float), np.abs(np.asarray(err, float))
    ok = err > 0
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)[0])


def finite(x):
    return x if (isinstance(x, (int, float)) and math.isfinite(x)) else None
