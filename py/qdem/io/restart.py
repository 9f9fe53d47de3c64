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
import errno
import itertools
import os
import zipfile

import numpy as np

from ..mpi import ranks as parallel
from ..world import defaultWorld

FORMAT = 1

_loads = itertools.count(1)  # numbers each loadState: a VtkRecorder follows each once


def _markLoaded(world):
    """The world's state was loaded at its present step: its VtkRecorders
    (qdem.yade.recorder, VtkRecorder._sync) keep their frames up to this step - from
    their .pvd when they have none, a restart in a new process - and time
    their next frame from it, on their period grid.  (Not imported from
    qdem.yade.recorder: qdem without YADE has no recorder.)"""
    world._stateLoaded = (int(world.core.iter), float(world.core.time), next(_loads))


def _writeNpz(path, arrays):
    """np.savez to a temporary name, then renamed to `path`; an error names
    `path` (not the temporary name) and what to do."""
    d = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(d):
        raise FileNotFoundError(errno.ENOENT, "saveState: cannot write %s: the directory %s does not exist; "
                                              "create it first (os.makedirs(%r, exist_ok=True)) or save elsewhere"
                                % (path, d, os.path.dirname(path) or d))
    tmp = path + ".tmp.npz"
    try:
        np.savez(tmp, **arrays)
        os.replace(tmp, path)
    except OSError as e:  # no permission, disk full, a directory named like the file
        if os.path.exists(tmp):
            os.remove(tmp)
        raise type(e)(e.errno, "saveState: cannot write %s: %s; save to a path you can write to"
                      % (path, e.strerror or e)) from None


def saveState(path, world=None, **extra):
    """Write the world's state to `path` (a .npz file; '~' is the home
    directory; the directory must exist).  `extra` numeric or string values
    (e.g. O.time of the script) are stored along and returned by loadState."""
    path = os.path.expanduser(os.fspath(path))
    core = (world or defaultWorld()).core
    if core.mpiSize > 1:
        core.gatherState()  # collective: every rank calls saveState; rank 0 writes (doc/parallel.md)
    arrays = {"qdem:" + k: np.frombuffer(v, dtype=np.uint8) for k, v in core.saveState().items()}
    arrays["format"] = np.array(FORMAT)
    for k, v in extra.items():
        arrays["extra:" + k] = np.asarray(v)
    # Rank 0 writes; a failure there is raised on every rank (parallel.writerDoes).
    parallel.writerDoes(lambda: _writeNpz(path, arrays), "saveState(%r)" % path)


def loadState(path, world=None):
    """Load a state written by saveState into `world` (built with the same
    pieces).  Returns the `extra` values saved with it as a dict.  The world's
    VtkRecorders go on with the series the saved run wrote (_markLoaded)."""
    path = os.path.expanduser(os.fspath(path))
    w = world or defaultWorld()
    core = w.core
    try:
        data = np.load(path)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise ValueError("loadState: %s is not a QDEM state file (%s)" % (path, e)) from None
    with data:
        if "format" not in data.files or int(data["format"]) != FORMAT:
            raise ValueError("loadState: %s is not a QDEM state file of format %d" % (path, FORMAT))
        core.loadState({k[5:]: data[k].tobytes() for k in data.files if k.startswith("qdem:")})
        _markLoaded(w)
        return {k[6:]: data[k].item() if data[k].ndim == 0 else data[k] for k in data.files if k.startswith("extra:")}
