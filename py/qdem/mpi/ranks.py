"""QDEM across MPI ranks (doc/parallel.md).

The same script runs serially and under ``mpiexec -n P yade -n -x script.py``:
every rank builds the whole scene, and at its first step the QdemEngine splits
the QDEM nodes and tetrahedra along the Hilbert curve, one contiguous share
per rank (qdem._core.World.setCommunicator).  Each rank computes its share and
exchanges its halo; walls, boxes, facets and YADE spheres (clump members too)
are known on every rank, their forces summed over the ranks, so every rank's
copy of YADE moves alike.  After each step (QdemEngine.gatherPeriod)
every rank learns every node's state again, so scripts read ``piece.pos`` as
usual; rank 0 alone writes files.

Below the YADE host (qdem.yade): nothing here imports YADE.  Under yade.mpy
the host's glue (qdem.yade.mpy) splits the world over mpy's communicator;
this module only tells whether yade.mpy is in use (mpyModule)."""
import atexit
import os
import sys

from .. import _core
from .. import world as _world


_launched = None  # launchedSize(): mpiexec's environment does not change within a process


def launchedSize():
    """Number of ranks mpiexec started (1 without mpiexec), read from the
    environment so that a serial run never loads MPI (once: every step asks)."""
    global _launched
    if _launched is None:
        _launched = 1
        for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"):
            v = os.environ.get(var)
            if v:
                try:
                    _launched = int(v)
                    break
                except ValueError:
                    pass
    return _launched


def rank():
    """This process's rank among those mpiexec started (0 without mpiexec)."""
    for var in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "MV2_COMM_WORLD_RANK"):
        v = os.environ.get(var)
        if v:
            try:
                return int(v)
            except ValueError:
                pass
    return 0


def isWriter():
    """True on the rank that writes files (rank 0, or the only process)."""
    return rank() == 0


MPY_UNSPLIT = (
    "qdem: the script imported yade.mpy and runs on %d ranks, but steps QDEM outside mp.mpirun (O.run, O.step): "
    "under yade.mpy step with mp.mpirun(n) only (QDEM then joins mpy's split: doc/parallel.md, 'Under "
    "yade.mpy'), or do not import yade.mpy and run the script under plain `mpiexec -n P yade -n -x script.py`.")


def mpyModule():
    """yade.mpy when the script runs under it on more than one rank, else None
    (read from sys.modules: this never imports YADE or MPI)."""
    mp = sys.modules.get("yade.mpy")
    if mp is None or getattr(mp, "comm", None) is None or (getattr(mp, "numThreads", 1) or 1) <= 1:
        return None
    return mp


def _mpyInUse():
    return mpyModule() is not None


def requireMpi(size):
    """Raises the error naming the fix when this build of qdem has no MPI."""
    if not _core.hasMPI:
        raise RuntimeError(
            "qdem: started by mpiexec with %d ranks, but this build of qdem has no MPI (Open MPI or mpi4py were "
            "missing when it was built): apt-get install libopenmpi-dev openmpi-bin python3-mpi4py, then make "
            "build again (or run without mpiexec)" % size)


def attach(world):
    """Splits `world` across the ranks a plain mpiexec started (a no-op
    serially, and when it is already split).  Called by QdemEngine at its
    first step; under yade.mpy the engine splits over mpy's communicator
    instead (qdem.yade.mpy.MpyCoupling.attach), once mpy has split the scene:
    before that, stepping QDEM on several ranks is refused here."""
    mp = mpyModule()
    size = mp.numThreads if mp is not None else launchedSize()
    core = world.core
    if size <= 1 or core.mpiSize > 1:
        return
    requireMpi(size)
    if mp is not None:  # yade.mpy imported, its scene not split (mp.mpirun not called): stepped by O.run
        raise RuntimeError(MPY_UNSPLIT % size)
    # (mpi4py imported here, not at the top: a serial run never loads MPI)
    from mpi4py import MPI
    core.setCommunicator(MPI.COMM_WORLD)
    global _plainSplit
    _plainSplit = True


def _plainMpiRanks():
    """Number of ranks of a plain mpiexec run whose every rank runs the script
    (1 serially and under yade.mpy, whose workers do not run it)."""
    size = launchedSize()
    if size <= 1 or _mpyInUse():
        return 1
    return size


def checkWritable(path, what):
    """Raises OSError naming `path` when its directory is missing or not
    writable.  (YADE's gzip writer loops for good on a stream that failed to
    open - O.save('missing/x.yade.gz') hung - and a bare FileNotFoundError
    named a temporary file the user never gave.)"""
    d = os.path.dirname(os.path.abspath(os.path.expanduser(path)))
    if not os.path.isdir(d):
        raise OSError("%s: cannot write %r: the directory %r does not exist (create it first, e.g. "
                      "os.makedirs(%r, exist_ok=True))" % (what, path, d, d))
    if not os.access(d, os.W_OK | os.X_OK):
        raise OSError("%s: cannot write %r: the directory %r is not writable (choose another one)" % (what, path, d))


def writerDoes(action, what):
    """Runs action() on the rank that writes files (rank 0; the only process
    serially) and returns its result there (None on the other ranks).  Under
    mpiexec every rank calls this (collective): a failure on the writer is
    raised on every rank, with the writer's message.  Before, a write that
    failed on rank 0 alone (a missing directory, a full disk) stopped rank 0's
    script while the others waited in the next step's exchange for good."""
    result, err = None, None
    if isWriter():
        try:
            result = action()
        except Exception as e:  # (re-raised below, on every rank)
            err = e
    if _plainMpiRanks() > 1:
        from mpi4py import MPI
        msg = MPI.COMM_WORLD.bcast(None if err is None else "%s: %s" % (type(err).__name__, err), root=0)
        if msg is not None and err is None:
            raise RuntimeError("%s failed on rank 0, the rank that writes the files: %s" % (what, msg))
    if err is not None:
        raise err
    return result


def abortOnError():
    """Under a plain mpiexec run of several ranks: an error that ends the
    script on one rank ends the job (MPI_Abort), with its message.  YADE
    prints a script's uncaught error and calls sys.exit(1); the other ranks
    then waited for good in the next step's exchange (a typo inside
    ``if rank == 0:`` hung the job until its time limit).  Installed when
    qdem is imported; a no-op serially and under yade.mpy."""
    if _plainMpiRanks() <= 1 or getattr(sys.exit, "_qdemAbort", False):
        return
    plainExit = sys.exit

    def exitOrAbort(code=None):
        if code not in (None, 0) and _plainMpiRanks() > 1:  # (yade.mpy may have been imported since)
            sys.stderr.write("qdem: rank %d of %d stopped with an error (above); stopping every rank "
                             "(MPI_Abort) rather than leave the others waiting for it\n" % (rank(), launchedSize()))
            sys.stderr.flush()
            from mpi4py import MPI
            MPI.COMM_WORLD.Abort(code if isinstance(code, int) else 1)
        _agreeOnScriptEnd()  # (yade -x ends by sys.exit(0) and runs no atexit handler)
        plainExit(code)
    exitOrAbort._qdemAbort = True
    sys.exit = exitOrAbort
    atexit.register(_agreeOnScriptEnd)  # (plain Python scripts under mpiexec)
    if "yade.mpy" not in sys.modules:
        sys.meta_path.insert(0, _MpyEndHook())
    plainHook = sys.excepthook

    def hookThenAbort(t, v, tb):
        plainHook(t, v, tb)
        exitOrAbort(1)
    sys.excepthook = hookThenAbort


_endAgreed = False
_plainSplit = False  # a world was split over plain mpiexec's ranks (not yade.mpy's)


class _MpyEndHook:
    """Under plain mpiexec YADE ends a script by importing yade.mpy (whose
    import waits for every rank) and calling mp.disconnect() on rank 0 and
    mp.spawnedProcessWaitCommand() on the others; it runs no atexit handler.
    This import hook makes every rank first agree that it is at the end
    (_agreeOnScriptEnd), before the import and before those two: a rank still
    stepping is told so, instead of waiting for good."""

    def find_spec(self, name, path=None, target=None):
        if name != "yade.mpy":
            return None
        for f in sys.meta_path:
            if f is self or not hasattr(f, "find_spec"):
                continue
            spec = f.find_spec(name, path, target)
            if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
                plainExec = spec.loader.exec_module

                def execThenWrap(module):
                    _agreeOnScriptEnd()  # (the import itself waits for every rank)
                    plainExec(module)
                    _wrapMpyEnd(module)
                spec.loader.exec_module = execThenWrap
                return spec
        return None


def _wrapMpyEnd(mp):
    for name in ("disconnect", "spawnedProcessWaitCommand"):
        f = getattr(mp, name, None)
        if not callable(f):
            continue

        def agreedFirst(*a, _f=f, **k):
            _agreeOnScriptEnd()
            return _f(*a, **k)
        setattr(mp, name, agreedFirst)


def _agreeOnScriptEnd():
    """At exit: every rank must be at the end of the script too.  A rank still
    stepping or saving (more O.run steps on one rank, a save inside
    ``if rank == 0:``) raised on both sides, naming the two calls; here that
    ends the job (MPI_Abort) rather than leave MPI's finalisation waiting."""
    global _endAgreed
    if not _plainSplit or _endAgreed:
        return
    _endAgreed = True
    w = _world._default
    try:
        if w is not None and w.core.mpiSize > 1:
            w.core.agreeOnScriptEnd()
    except Exception as e:  # the other ranks were told the same
        sys.stderr.write("qdem: rank %d of %d: %s\n" % (rank(), launchedSize(), e))
        sys.stderr.flush()
        from mpi4py import MPI
        MPI.COMM_WORLD.Abort(1)


# (these counts are per run, not per rank: the same on every rank)
_NOT_SUMMED = ("viscousIterations", "viscousIterationsTotal", "viscousWarmStart")


def summedCounts(core):
    """core.contactCounts summed over the ranks (each rank counts the contacts
    it computed); the counts themselves on one process.  Collective under MPI."""
    c = dict(core.contactCounts)
    if core.mpiSize <= 1:
        return c
    from mpi4py import MPI
    keys = sorted(c)
    every = MPI.COMM_WORLD.allgather([c[k] for k in keys])
    return {k: (c[k] if k in _NOT_SUMMED else sum(r[i] for r in every)) for i, k in enumerate(keys)}


