"""Restarts: save a world's dynamic state to a file and load it into the same
scene built again, so that a run longer than a job's time limit goes on
exactly where it stopped (YADE's O.save does not see QDEM's state).

    qdem.saveState("run.qdem.npz")          # e.g. from a PyRunner, with O.save
    ...                                     # next job: build the same scene, then
    qdem.loadState("run.qdem.npz")

Saved: node positions and velocities, external forces and blocked DOFs,
every contact history (tangential springs, wall sides, contacts born deep;
YADE spheres' with pieces too, by sphere id and piece), sleeping pieces, the
QDEM clock and step count, energy sums.  Not saved: the meshes, materials
and settings (the script makes them again; a different scene is refused,
naming the difference).  The file is written to a
temporary name and renamed: a run stopped while saving never leaves a broken
file behind."""
import os
import zipfile

import numpy as np

from . import parallel
from .world import defaultWorld

FORMAT = 1


def saveState(path, world=None, **extra):
    """Write the world's state to `path` (a .npz file).  `extra` numeric or
    string values (e.g. O.time of the script) are stored along and returned by
    loadState."""
    core = (world or defaultWorld()).core
    if core.mpiSize > 1:
        core.gatherState()  # collective: every rank calls saveState; rank 0 writes (doc/parallel.md)
    arrays = {"qdem:" + k: np.frombuffer(v, dtype=np.uint8) for k, v in core.saveState().items()}
    arrays["format"] = np.array(FORMAT)
    for k, v in extra.items():
        arrays["extra:" + k] = np.asarray(v)
    if not parallel.isWriter():
        return
    tmp = path + ".tmp.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def loadState(path, world=None):
    """Load a state written by saveState into `world` (built with the same
    pieces).  Returns the `extra` values saved with it as a dict."""
    core = (world or defaultWorld()).core
    try:
        data = np.load(path)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise ValueError("loadState: %s is not a QDEM state file (%s)" % (path, e)) from None
    with data:
        if "format" not in data.files or int(data["format"]) != FORMAT:
            raise ValueError("loadState: %s is not a QDEM state file of format %d" % (path, FORMAT))
        core.loadState({k[5:]: data[k].tobytes() for k in data.files if k.startswith("qdem:")})
        return {k[6:]: data[k].item() if data[k].ndim == 0 else data[k] for k in data.files if k.startswith("extra:")}
