"""qdem.yade: QDEM inside YADE - the engine in O.engines (engine), the VTK
recorder (recorder), the scene's life cycle (lifecycle: O.save/O.load/O.reset
and QDEM's errors), reading YADE's bodies and gravity (glue), the coupling
with YADE spheres (spheres) and with yade.mpy (mpy), and the set-up checks
(setupcheck).

Needs a running YADE; the layers below it (the model, qdem.mpi, qdem.io) do
not.  Inside it the modules import one another one way only: enginemeta,
glue < spheres < mpy; lifecycle < setupcheck < recorder < engine.  The
engines saved with a scene register with lifecycle (lifecycle.savedWithScene)
instead of lifecycle importing them."""
from . import lifecycle
from .engine import QdemEngine
from .mpy import assignSubdomains
from .recorder import VtkRecorder
from .setupcheck import SetupError

__all__ = ["QdemEngine", "VtkRecorder", "SetupError", "assignSubdomains"]
