"""Shared set-up of the Python benchmarks: a floor wall, step timing, what else
the machine was doing during each timed run (the same rule as
scripts/bench/MachineLoad.hpp), and min / median / max of repeated runs."""
import math
import os
import resource
import statistics
import time

import numpy as np

from qdem import _core


def floorAndGravity(world, g=9.80665, young=None):
    """A fixed floor wall at z = 0 (one-sided, facing +z) and gravity -g z;
    `young`: the floor's Young modulus (None: the Obstacle's default)."""
    floor = _core.Obstacle()
    floor.kind, floor.bodyId, floor.axis, floor.sense = 0, 0, 2, 1
    if young is not None:
        floor.young = young
    world.core.setObstacles([floor])
    world.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    world.core.gravity = (0, 0, -g)


def msPerStep(world, steps, dt=6.4e-6, warmup=3):
    """Milliseconds per step of `steps` core steps after a short warm-up."""
    world.core.step(dt, warmup)
    t = time.perf_counter()
    world.core.step(dt, steps)
    return 1e3 * (time.perf_counter() - t) / steps


# --- machine load ---------------------------------------------------------------------------------------------

def _busySeconds():
    """Busy seconds of all CPUs since boot (user, nice, system, irq, softirq, steal)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:9]]
    return (sum(v) - v[3] - v[4]) / os.sysconf("SC_CLK_TCK")


def _ownCpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _load1():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


class _OwnLoad:
    """This process's share of the 1-minute load average: its CPU use (cores)
    averaged with the kernel's 60 s time constant."""
    ema, lastWall, lastCpu = 0.0, None, 0.0

    @classmethod
    def update(cls):
        wall, cpu = time.monotonic(), _ownCpu()
        if cls.lastWall is not None and wall > cls.lastWall:
            w = math.exp(-(wall - cls.lastWall) / 60.0)
            cls.ema = w * cls.ema + (1 - w) * (cpu - cls.lastCpu) / (wall - cls.lastWall)
        cls.lastWall, cls.lastCpu = wall, cpu
        return cls.ema


MAX_LOAD, MAX_OTHERS = 1.5, 0.2
BUSY_RULE = {"max_other_cores": MAX_OTHERS,
             "note": "busy: other processes used more than 0.2 cores during the run (all CPUs' busy time less "
                     "this process's own); busy runs are left out of 'clean'.  The 1-minute load average is "
                     "recorded but does not decide: it lags by a minute and still holds the benchmark's own "
                     "set-up and the run before it"}


class LoadProbe:
    """Start before a timed run; finish(wall) after it gives the run's load record."""

    def __init__(self):
        self.own = _OwnLoad.update()
        self.load1 = _load1()
        self.busy0, self.own0 = _busySeconds(), _ownCpu()

    def finish(self, wall):
        others = max(0.0, (_busySeconds() - self.busy0) - (_ownCpu() - self.own0)) / wall if wall > 0 else 0.0
        othersLoad = max(0.0, self.load1 - self.own)
        return {"load1": round(self.load1, 2), "own_load": round(self.own, 2), "other_cores": round(others, 2),
                "load1_less_own": round(othersLoad, 2), "own_cpu_s": _ownCpu() - self.own0,
                "busy": others > MAX_OTHERS}


def stats(values):
    """{"n", "min", "median", "max"} of the values, or None without any
    (nothing measured is written as null, never as a zero)."""
    v = [x for x in values if x is not None]
    if not v:
        return None
    return {"n": len(v), "min": min(v), "median": statistics.median(v), "max": max(v)}


def summarise(runs, keys):
    """clean / all statistics of each key over a list of run records (each
    with a 'busy' flag): the figures every Python benchmark here reports."""
    return {"clean": {k: stats([r.get(k) for r in runs if not r["busy"]]) for k in keys},
            "all": {k: stats([r.get(k) for r in runs]) for k in keys}}


def best(summary, key, stat="median"):
    """(value, which runs) of a key: the quiet runs' figure, else all runs' (said so)."""
    if summary["clean"].get(key):
        return summary["clean"][key][stat], "quiet runs"
    if summary["all"].get(key):
        return summary["all"][key][stat], "all runs (every run busy)"
    return None, "not measured"


def timedWindow(world, dt, steps):
    """`steps` core steps of `dt`, timed: a LoadProbe record with the wall and
    CPU seconds and the load averages before and after, the viscous solve's
    CG iterations summed over the steps, and each phase timer's seconds summed
    (the shogi time-to-solution and preconditioner scripts' timed window)."""
    its, phases = 0, {}
    loadBefore = os.getloadavg()
    probe = LoadProbe()
    cpu0, t0 = time.process_time(), time.perf_counter()
    for _ in range(steps):
        world.core.step(dt, 1)
        its += world.core.counts.get("viscousIterations", 0)
        for k, v in world.core.timings.items():
            phases[k] = phases.get(k, 0.0) + v
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    rec = probe.finish(wall)
    rec.update(loadavg_before=list(loadBefore), loadavg_after=list(os.getloadavg()), wall_s=wall, cpu_s=cpu)
    return rec, its, phases
