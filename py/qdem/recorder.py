"""VtkRecorder: a YADE engine writing the QDEM pieces as a VTU time series."""
import os

import numpy as np
from yade import PyRunner

from . import lifecycle
from .attrs import Attr, AttrObject, documented
from .stress import vonMises
from .vtu import writePvd, writeVtu
from .world import defaultWorld
from .yadeclass import EngineMeta


def writeFrame(world, path):
    """One VTU of every piece: displacement, velocity, von Mises stress, piece id."""
    core = world.core
    stress = core.stress()
    writeVtu(path, core.pos, core.tets,
             pointData={"displacement": core.pos - core.refPos, "velocity": core.vel,
                        "piece": core.nodePiece},
             cellData={"vonMises": vonMises(stress), "stress": stress, "piece": core.tetPiece})


@documented
class VtkRecorder(PyRunner, metaclass=EngineMeta):
    """Writes ``<fileBase>NNNNNN.vtu`` every ``iterPeriod`` steps and keeps
    ``<fileBase>.pvd`` (open it in ParaView) up to date.  NNNNNN and the frame
    times are the QDEM world's step count and time; ``frames`` lists (time,
    file) of the frames so far (set it after a restart to keep the series)."""

    fileBase = Attr("out/qdem-", "Path prefix of the frames; the .pvd collection is fileBase + '.pvd', "
                                 "a trailing '-', '_' or '.' dropped (out/qdem-000100.vtu, out/qdem.pvd).")

    _public = ("record", "pvdPath", "dict")

    def __init__(self, world=None, qdemId=None, **kw):
        PyRunner.__init__(self)
        known = AttrObject.attrNames.__func__(type(self))
        for k, v in kw.items():
            if k in ("label", "dead", "iterPeriod", "virtPeriod", "realPeriod", "initRun") or k in known:
                setattr(self, k, v)
            else:
                raise TypeError("VtkRecorder: unknown keyword %r; known: world, label, dead, iterPeriod, "
                                "virtPeriod, realPeriod, initRun, %s" % (k, ", ".join(known)))
        if self.iterPeriod <= 0 and self.virtPeriod <= 0 and self.realPeriod <= 0:
            self.iterPeriod = 1000
        self.world = world or defaultWorld()
        self.frames = []
        self.qdemId = qdemId or lifecycle.newId()
        lifecycle.engines[self.qdemId] = self
        self.command = "import qdem.recorder; qdem.recorder._record('%s')" % self.qdemId

    def dict(self):
        """The recorder's settings as a plain dict."""
        return {k: getattr(self, k) for k in AttrObject.attrNames.__func__(type(self))}

    def savedState(self):
        """What O.save keeps of this recorder besides its PyRunner fields."""
        return {"kind": "VtkRecorder", "settings": self.dict(), "frames": [list(f) for f in self.frames],
                "label": self.label, "dead": bool(self.dead), "iterPeriod": self.iterPeriod,
                "virtPeriod": self.virtPeriod, "realPeriod": self.realPeriod, "initRun": self.initRun,
                "iterLast": self.iterLast, "virtLast": self.virtLast, "nDone": self.nDone, "nDo": self.nDo}

    @classmethod
    def fromSaved(cls, qdemId, st, runner=None):
        r = cls(qdemId=qdemId, **st["settings"])
        # nDone too: YADE's PeriodicEngine restarts its clock at its first call when nDone is 0
        for k in ("label", "dead", "iterPeriod", "virtPeriod", "realPeriod", "initRun", "iterLast", "virtLast",
                  "nDone", "nDo"):
            if k in st:
                setattr(r, k, st[k])
        r.frames = [tuple(f) for f in st.get("frames", [])]
        return r

    def record(self):
        """Write one frame now."""
        d = os.path.dirname(self.fileBase)
        if d:
            os.makedirs(d, exist_ok=True)
        # Named by the QDEM world's own step count and time, which a restart
        # (qdem.loadState) restores: a restarted run's frames go on the series.
        core = self.world.core
        path = "%s%06d.vtu" % (self.fileBase, core.iter)
        writeFrame(self.world, path)
        self.frames.append((core.time, os.path.basename(path)))
        writePvd(self.pvdPath(), self.frames)

    def pvdPath(self):
        """The ParaView collection: fileBase + '.pvd' (trailing '-', '_' or '.' dropped)."""
        base = self.fileBase[:-1] if self.fileBase.endswith((".", "-", "_")) else self.fileBase
        return base + ".pvd"


def _record(qdemId):
    rec = lifecycle.engineFor(qdemId)
    try:
        rec.record()
    except Exception as e:
        lifecycle._pending.append(e)
        raise
