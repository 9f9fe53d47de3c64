"""Shared set-up of the Python benchmarks: a floor wall and step timing."""
import time

import numpy as np

from qdem import _core


def floorAndGravity(world, g=9.80665):
    """A fixed floor wall at z = 0 (one-sided, facing +z) and gravity -g z."""
    floor = _core.Obstacle()
    floor.kind, floor.bodyId, floor.axis, floor.sense = 0, 0, 2, 1
    world.core.setObstacles([floor])
    world.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    world.core.gravity = (0, 0, -g)


def msPerStep(world, steps, dt=6.4e-6, warmup=3):
    """Milliseconds per step of `steps` core steps after a short warm-up."""
    world.core.step(dt, warmup)
    t = time.perf_counter()
    world.core.step(dt, steps)
    return 1e3 * (time.perf_counter() - t) / steps
