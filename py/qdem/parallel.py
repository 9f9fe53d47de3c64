"""QDEM across MPI ranks (doc/parallel.md).

The same script runs serially and under ``mpiexec -n P yade -n -x script.py``:
every rank builds the whole scene, and at its first step the QdemEngine splits
the QDEM nodes and tetrahedra along the Hilbert curve, one contiguous share
per rank (qdem._core.World.setCommunicator).  Each rank computes its share and
exchanges its halo; walls, boxes, facets and YADE spheres (clump members too)
are known on every rank, their forces summed over the ranks, so every rank's
copy of YADE moves alike.  After each step (QdemEngine.gatherPeriod)
every rank learns every node's state again, so scripts read ``piece.pos`` as
usual; rank 0 alone writes files."""
import os

from . import _core


def launchedSize():
    """Number of ranks mpiexec started (1 without mpiexec), read from the
    environment so that a serial run never loads MPI."""
    for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"):
        v = os.environ.get(var)
        if v:
            try:
                return int(v)
            except ValueError:
                pass
    return 1


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


def _mpyInUse():
    from . import mpyglue
    return mpyglue.module() is not None


def attach(world):
    """Splits `world` across the ranks mpiexec started (a no-op serially, and
    when it is already split).  Called by QdemEngine at its first step."""
    from . import mpyglue
    mp = mpyglue.module()
    size = mp.numThreads if mp is not None else launchedSize()
    core = world.core
    if size <= 1 or core.mpiSize > 1:
        return
    if not _core.hasMPI:
        raise RuntimeError(
            "qdem: started by mpiexec with %d ranks, but this build of qdem has no MPI (Open MPI or mpi4py were "
            "missing when it was built): apt-get install libopenmpi-dev openmpi-bin python3-mpi4py, then make "
            "build again (or run without mpiexec)" % size)
    if mp is not None:
        from yade import O
        if not getattr(O, "splitted", False):
            raise RuntimeError(MPY_UNSPLIT % size)
        mpyglue.attach(world)  # over mpy's communicator, its master owning no node
        return
    from mpi4py import MPI
    core.setCommunicator(MPI.COMM_WORLD)


def summedCounts(core):
    """core.contactCounts summed over the ranks (each rank counts the contacts
    it computed); the counts themselves on one process.  Collective under MPI."""
    c = dict(core.contactCounts)
    if core.mpiSize <= 1:
        return c
    from mpi4py import MPI
    keys = sorted(c)
    every = MPI.COMM_WORLD.allgather([c[k] for k in keys])
    return {k: sum(r[i] for r in every) for i, k in enumerate(keys)}


def assignSubdomains(world=None):
    """Under yade.mpy, before ``mp.mpirun``: sets each YADE sphere's and
    clump's ``Body.subdomain`` from QDEM's own split, so that it lives on the
    worker owning the piece surface nearest to it (mpyglue.assignSubdomains;
    doc/parallel.md, 'Under yade.mpy').  A no-op serially and under plain
    mpiexec; returns {rank: bodies placed}."""
    from . import mpyglue
    return mpyglue.assignSubdomains(world)
