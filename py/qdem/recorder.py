"""VtkRecorder: a YADE engine writing the QDEM pieces as a VTU time series
for ParaView (VTK's XML writer, compressed; doc/yade.md)."""
import math
import os

import numpy as np
from yade import PyRunner

from . import lifecycle, parallel
from .attrs import Attr, AttrObject, documented, integer, number
from .stress import vonMises
from .vtu import TENSOR6, writePvd, writeVtu
from .world import FollowsDefaultWorld
from .yadeclass import EngineMeta

_STRESS_TO_PARAVIEW = [0, 1, 2, 5, 3, 4]  # core xx yy zz yz xz xy -> ParaView XX YY ZZ XY YZ XZ


def rigidlessDisplacement(world):
    """Node displacements with each piece's best-fit rigid motion removed (mass
    weighted Kabsch fit of the reference shape to the current one): what the
    material feels, where 'displacement' also holds the flight of the piece."""
    core = world.core
    out = np.empty_like(core.pos)
    for p in world.pieces:
        sl = p.nodeSlice
        m = core.mass[sl][:, None]
        X, x = core.refPos[sl], core.pos[sl]
        Xc, xc = (m * X).sum(0) / m.sum(), (m * x).sum(0) / m.sum()
        H = ((X - Xc) * m).T @ (x - xc)
        U, _, Vt = np.linalg.svd(H)
        d = np.sign(np.linalg.det(U @ Vt)) or 1.0
        R = (U @ np.diag([1.0, 1.0, d]) @ Vt).T
        out[sl] = x - ((X - Xc) @ R.T + xc)
    return out


def volumeRatio(core):
    """det F of each tet (current / reference volume; <= 0: inverted)."""
    x, X, t = core.pos, core.refPos, core.tets
    def vol(p):
        return np.einsum("ij,ij->i", np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), p[t[:, 3]] - p[t[:, 0]])
    return vol(x) / vol(X)


def writeFrame(world, path):
    """One VTU of every piece.  Points: displacement (from the reference shape,
    rigid motion included), deformation (rigid motion removed), velocity, piece.
    Cells: stress (Cauchy, elastic + viscous, components XX YY ZZ XY YZ XZ),
    vonMises, volumeRatio (det F; <= 0 marks an inverted element), piece."""
    core = world.core
    stress = core.stress()
    writeVtu(path, core.pos, core.tets,
             pointData={"displacement": core.pos - core.refPos, "deformation": rigidlessDisplacement(world),
                        "velocity": core.vel, "piece": core.nodePiece},
             cellData={"stress": stress[:, _STRESS_TO_PARAVIEW], "vonMises": vonMises(stress),
                       "volumeRatio": volumeRatio(core), "piece": core.tetPiece},
             componentNames={"stress": TENSOR6, "displacement": "XYZ", "deformation": "XYZ", "velocity": "XYZ"})


def _fileBase(v):
    if not isinstance(v, (str, os.PathLike)) or isinstance(os.fspath(v), bytes):
        return "must be a path prefix (a string such as 'out/qdem-'), not %s" % type(v).__name__
    if not os.fspath(v):
        return ("must not be empty: it prefixes the frame files (an empty one writes bare step numbers into the "
                "current directory); use e.g. 'out/qdem-' or 'frames/'")
    if "\0" in os.fspath(v):
        return "must not contain a NUL character"
    return None


_fileBase.convert = os.fspath


@documented
class VtkRecorder(FollowsDefaultWorld, PyRunner, metaclass=EngineMeta):
    """Writes ``<fileBase>NNNNNN.vtu`` frames and keeps ``<fileBase>.pvd`` (open it
    in ParaView) up to date.  NNNNNN is the step count and the .pvd time the
    simulated time at the end of the step the frame shows (O.iter and O.time
    once the step is done; the QDEM clock, which also goes on across a
    qdem.loadState restart).  A frame of the initial state (step 0, t = 0) is
    written before the first step.  ``frames`` lists (time, file) so far."""

    fileBase = Attr("out/qdem-", "Path prefix of the frames; the .pvd collection is fileBase + '.pvd', "
                                 "a trailing '-', '_' or '.' dropped (out/qdem-000100.vtu, out/qdem.pvd); "
                                 "a directory ('out/run/') gets out/run/000100.vtu and out/run/frames.pvd.",
                    _fileBase)
    iterPeriod = Attr(1000, "A frame every this many steps (at step counts that are multiples of it); "
                            "0 = none by step count.", integer(0, extra=" (0 = none by step count)"))
    virtPeriod = Attr(0.0, "A frame every this much simulated time [s] (0 = none by time).", number(0))

    _public = ("record", "pvdPath", "dict")
    _yadeAttrs = ("label", "dead")

    def __init__(self, world=None, qdemId=None, **kw):
        PyRunner.__init__(self)
        known = AttrObject.attrNames.__func__(type(self))
        for k, v in kw.items():
            if k in self._yadeAttrs or k in known:
                setattr(self, k, v)
            else:
                raise TypeError("VtkRecorder: unknown keyword %r; known: world, label, dead, %s"
                                % (k, ", ".join(known)))
        # YADE calls it every step; it decides on the QDEM clock when a frame is due.
        PyRunner.iterPeriod.__set__(self, 1)
        self._setWorld(world)
        self.frames = []
        self._last = None  # (step, time) of the last frame
        self.qdemId = qdemId or lifecycle.newId()
        self.command = "import qdem.recorder; qdem.recorder._record('%s')" % self.qdemId

    def _worldReplaced(self, old, new):
        """O.reset() replaced the default world: the new scene's frames start a new collection."""
        self.frames = []
        self._last = None

    def __repr__(self):
        return "<VtkRecorder%s at %#x>" % (" %r" % self.label if self.label else "", id(self))

    def dict(self):
        """The recorder's settings as a plain dict."""
        return {k: getattr(self, k) for k in AttrObject.attrNames.__func__(type(self))}

    def savedState(self):
        """What O.save keeps of this recorder besides its PyRunner fields."""
        return {"kind": "VtkRecorder", "settings": self.dict(), "frames": [list(f) for f in self.frames],
                "last": list(self._last) if self._last else None, "label": self.label, "dead": bool(self.dead)}

    @classmethod
    def fromSaved(cls, qdemId, st, runner=None):
        r = cls(qdemId=qdemId, **st["settings"])
        r.label, r.dead = st.get("label", ""), st.get("dead", False)
        r.frames = [tuple(f) for f in st.get("frames", [])]
        r._last = tuple(st["last"]) if st.get("last") else None
        return r

    def due(self):
        """Is a frame due for the world's present state?"""
        core = self.world.core
        if self._last is None:
            return True
        if core.iter == self._last[0]:
            return False
        if self.iterPeriod and core.iter % int(self.iterPeriod) == 0:
            return True
        if self.virtPeriod and math.floor(core.time / self.virtPeriod) > math.floor(self._last[1] / self.virtPeriod):
            return True
        return False

    def record(self):
        """Write one frame now (under MPI: rank 0 writes, every rank keeps the list)."""
        core = self.world.core
        path = "%s%06d.vtu" % (self.fileBase, core.iter)
        if core.mpiSize > 1 and not core.stateCurrent:
            core.gatherAll()  # collective: every rank records at the same steps
        if parallel.isWriter():
            d = os.path.dirname(self.fileBase)
            try:
                if d:
                    os.makedirs(d, exist_ok=True)
                writeFrame(self.world, path)
            except OSError as e:  # a file where the directory should be, no permission, disk full
                raise type(e)(e.errno, "VtkRecorder: cannot write the frame %s (fileBase=%r): %s; choose a "
                                       "fileBase in a directory you can write to"
                              % (path, self.fileBase, e.strerror or e)) from None
        self.frames = [f for f in self.frames if f[1] != os.path.basename(path)]  # a rewritten step replaces its frame
        self.frames.append((core.time, os.path.basename(path)))
        self._last = (core.iter, core.time)
        if parallel.isWriter():
            writePvd(self.pvdPath(), self.frames)

    def pvdPath(self):
        """The ParaView collection: fileBase + '.pvd' (trailing '-', '_' or '.' dropped)."""
        base = self.fileBase[:-1] if self.fileBase.endswith((".", "-", "_")) else self.fileBase
        if not os.path.basename(base):  # a directory: out/run/ -> out/run/frames.pvd, not a hidden out/run/.pvd
            base = os.path.join(base, "frames")
        return base + ".pvd"


def initialFrames(world):
    """Called by QdemEngine before the world's first step: every recorder of the
    world that has no frame yet writes the initial state (step 0, t = 0)."""
    from yade import O
    for e in O.engines:
        if isinstance(e, VtkRecorder) and e.world is world and e._last is None and not e.dead:
            e.record()


def _record(qdemId):
    rec = lifecycle.engineFor(qdemId)
    try:
        if rec.due():
            rec.record()
    except Exception as e:
        lifecycle._pending.append(e)
        raise
