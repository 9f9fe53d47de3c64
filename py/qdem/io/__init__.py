"""qdem.io: what goes into and out of files - CAD models meshed with gmsh
(cad), restart files of a world's dynamic state (restart), VTK unstructured
grids (vtu), pictures (render: VTK, off screen) and energy plots (plot:
matplotlib).

Above the model (meshes, materials, pieces, world) and qdem.mpi (rank 0
writes), below the YADE host.  render and plot are loaded on first use
(``qdem.io.render.snapshot(...)`` needs no ``import qdem.io.render``): VTK and
matplotlib take a second to import, which ``import qdem`` does not pay."""
import importlib

from .cad import meshCad
from .restart import loadState, saveState
from .vtu import readVtu, writePvd, writeVtu

__all__ = ["meshCad", "saveState", "loadState", "readVtu", "writeVtu", "writePvd"]

_LAZY = ("render", "plot")


def __getattr__(name):
    if name in _LAZY:
        return importlib.import_module("." + name, __name__)
    raise AttributeError("module %r has no attribute %r" % (__name__, name))


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
