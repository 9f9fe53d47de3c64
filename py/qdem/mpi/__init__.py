"""qdem.mpi: QDEM across MPI ranks (doc/parallel.md).

Which rank this is, which rank writes files, and the split of a world over
the ranks of a plain ``mpiexec -n P yade -n -x script.py`` run.  Nothing here
imports YADE: under YADE's own MPI mode the host's glue (qdem.yade.mpy) splits
the world over mpy's ranks and places the spheres (qdem.yade.mpy.assignSubdomains)."""
from .ranks import isWriter, launchedSize, rank, summedCounts

__all__ = ["rank", "isWriter", "launchedSize", "summedCounts"]
