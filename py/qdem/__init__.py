"""yade-qdem: deformable viscoelastic bodies for YADE, simulated with QDEM
(Quadruple Discrete Element Method) and colliding through their surfaces.

Typical use inside a YADE script::

    import qdem
    mat = qdem.QdemMat(young=1e7, viscosity=50)
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.5))
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * qdem.stableDt()["combined"]
"""
from . import _core
from ._core import StabilityError
from . import modes
from .material import QdemMat
from .mesh import Mesh, boxMesh, loadMesh, loadSurface, meshSurface, splitMesh
from .piece import Piece
from .remesh import improveMesh, meshQuality
from .restart import loadState, saveState
from .shapes import ballMesh
from .world import World, addPiece, defaultWorld, reset, stableDt
from . import parallel as _parallel

_parallel.abortOnError()  # under mpiexec: a script's error on one rank ends the job, not a hang

__version__ = "0.1.0"

try:  # the YADE-facing parts need a running YADE
    import yade  # noqa: F401
except ImportError:
    pass
else:
    from . import lifecycle as _lifecycle
    from .engine import QdemEngine
    from .recorder import VtkRecorder
    from .setupcheck import SetupError
    _lifecycle.install()  # O.save/O.load/O.reset carry QDEM; QDEM errors reach scripts as themselves

__all__ = ["QdemMat", "Mesh", "Piece", "World", "StabilityError", "QdemEngine", "VtkRecorder",
           "addPiece", "boxMesh", "loadMesh", "loadSurface", "meshSurface", "splitMesh", "defaultWorld",
           "reset", "stableDt", "saveState", "loadState", "ballMesh", "SetupError",
           "improveMesh", "meshQuality"]
