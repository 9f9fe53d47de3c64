"""yade-qdem: deformable viscoelastic bodies for YADE, simulated with QDEM
(Quadruple Discrete Element Method) and colliding through their surfaces.

Typical use inside a YADE script::

    import qdem
    mat = qdem.QdemMat(young=1e7, viscosity=50)
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.5))
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * qdem.stableDt()["combined"]

The package in layers, each importing only the layers below it
(doc/architecture.md, 'The Python package'): the model in qdem's own modules
(attrs, mesh, material, piece, world, ...), qdem.mpi, qdem.io, qdem.yade (needs
YADE), qdem.scenes, and this file, the user API, on top.
"""
import importlib

from . import _core
from ._core import StabilityError
StabilityError.__doc__ = (
    "Raised when a run would go unstable or give a wrong answer: O.dt above the stable step, an element "
    "stiffened or inverted beyond what O.dt resolves, a non-finite position or force, a node through a wall "
    "or deeper inside another piece than the contacts reach.  The message names the piece, element or node, "
    "the limit and the fix (doc/hard_cases.md).")
from . import _moved, modes
from .io import loadState, meshCad, saveState
from .material import QdemMat
from .mesh import Mesh, boxMesh, loadMesh, loadSurface, meshSurface, splitMesh
from .mpi import ranks as _ranks
from .piece import Piece
from .remesh import improveMesh, meshQuality
from .shapes import ballMesh
from .world import World, addPiece, defaultWorld, reset, stableDt

_moved.install()  # qdem.engine, qdem.shogi, ...: the old paths, deprecated
_ranks.abortOnError()  # under mpiexec: a script's error on one rank ends the job, not a hang

__version__ = "0.1.0"

try:  # the YADE-facing parts need a running YADE
    import yade  # noqa: F401
except ImportError:
    pass
else:
    from .yade import QdemEngine, SetupError, VtkRecorder, lifecycle as _lifecycle
    _lifecycle.install()  # O.save/O.load/O.reset carry QDEM; QDEM errors reach scripts as themselves

# Loaded on first use (``qdem.render.snapshot`` without ``import qdem.render``):
# VTK and matplotlib are imported only by a script that uses them.
_LAZY = {"render": "qdem.io.render", "plot": "qdem.io.plot"}


def __getattr__(name):
    if name in _LAZY:
        return importlib.import_module(_LAZY[name])
    if name in _moved.MOVED:  # an old module path (qdem.shogi, qdem.engine, ...): deprecated
        return _moved.moduleFor(name)
    raise AttributeError("module 'qdem' has no attribute %r" % name)


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = ["QdemMat", "Mesh", "Piece", "World", "StabilityError", "QdemEngine", "VtkRecorder",
           "addPiece", "boxMesh", "loadMesh", "loadSurface", "meshSurface", "meshCad", "splitMesh", "defaultWorld",
           "reset", "stableDt", "saveState", "loadState", "ballMesh", "SetupError",
           "improveMesh", "meshQuality"]
