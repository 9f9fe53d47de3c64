"""VtkRecorder: a YADE engine writing the QDEM pieces as a VTU time series
for ParaView (VTK's XML writer, compressed; doc/yade.md).

A series goes on across a restart: after qdem.loadState a recorder keeps the
frames the earlier run listed in the .pvd (up to the step loaded) and writes
its next frame on the same period grid.  Two live recorders that would write
one .pvd are refused; under yade-batch the default fileBase holds the job's
description, so that jobs do not overwrite each other's frames."""
import math
import os
import re
import warnings
import xml.etree.ElementTree as ElementTree
import zlib

import numpy as np
from yade import O, PyRunner
from yade.utils import TableParamReader

from ..attrs import Attr, AttrObject, documented, integer, number
from ..io.vtu import TENSOR6, writePvd, writeVtu
from ..mpi import ranks as parallel
from ..stress import vonMises
from ..world import FollowsDefaultWorld
from . import lifecycle
from .enginemeta import EngineMeta
from .setupcheck import SetupError

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


def _expandFileBase(v):
    """'~/x-' means the home directory, as in a shell (else a literal './~/' directory is made)."""
    return os.path.expanduser(os.fspath(v))


_fileBase.convert = _expandFileBase

DEFAULT_FILEBASE = "out/qdem-"


def batchDescription():
    """The description of the yade-batch job this process runs (the table's
    ``description`` column, or the one YADE makes of the job's parameters), or
    None outside yade-batch.  yade-batch puts ``table:line`` in the YADE_BATCH
    environment variable of each job (empty for a job without a table);
    ``readParamsFromTable`` copies the line's description to
    ``O.tags['description']``, which O.reset() empties: the table is read again
    then."""
    spec = os.environ.get("YADE_BATCH", "")
    if not spec:
        return None
    if O.tags.has_key("description") and O.tags["description"]:
        return O.tags["description"]
    table, _, line = spec.rpartition(":")
    try:
        return TableParamReader(table).paramDict()[int(line)]["description"]
    except Exception:  # (an unreadable table: yade-batch itself would have refused it)
        return "line" + line


def defaultFileBase():
    """'out/qdem-', or under yade-batch 'out/<job description>/qdem-': jobs of
    one batch run side by side in one directory and would otherwise write the
    same files (the last job's frames win, silently)."""
    d = batchDescription()
    if d is None:
        return DEFAULT_FILEBASE
    d = re.sub(r"[/\\\0]", "_", d).strip()  # one directory level, whatever the parameters hold
    if d in ("", ".", ".."):
        d = "job"
    if len(d) > 200:  # (as yade-batch shortens its log names: file names stop at 255 bytes)
        d = d[:200] + "_%08x" % zlib.crc32(d.encode())
    return "out/%s/qdem-" % d


class _FileBaseAttr(Attr):
    """fileBase: as given (with '~' expanded), else defaultFileBase() read when
    used, so that a recorder made before readParamsFromTable follows the job."""

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        v = obj.__dict__.get(self.name)
        return defaultFileBase() if v is None else v


@lifecycle.savedWithScene
@documented
class VtkRecorder(FollowsDefaultWorld, PyRunner, metaclass=EngineMeta):
    """Writes ``<fileBase>NNNNNN.vtu`` frames and keeps ``<fileBase>.pvd`` (open it
    in ParaView) up to date.  NNNNNN is the step count and the .pvd time the
    simulated time at the end of the step the frame shows (O.iter and O.time
    once the step is done; the QDEM clock, which also goes on across a
    qdem.loadState restart).  A frame of the initial state (step 0, t = 0) is
    written before the first step.  ``frames`` lists (time, file) so far.

    After ``qdem.loadState`` the series goes on: a new recorder (a new
    process) keeps the frames its .pvd lists up to the step loaded (those
    whose .vtu is still there), and the next frame is the next one on the
    period grid.  A run starting from step 0 starts a new .pvd.  Two live
    recorders whose fileBases give one .pvd are refused at the first frame."""

    fileBase = _FileBaseAttr(DEFAULT_FILEBASE,
                             "Path prefix of the frames; the .pvd collection is fileBase + '.pvd', "
                             "a trailing '-', '_' or '.' dropped (out/qdem-000100.vtu, out/qdem.pvd); "
                             "a directory ('out/run/', or an existing directory 'out/run') gets "
                             "out/run/000100.vtu and out/run/frames.pvd; '~' is the home directory. "
                             "Unset under yade-batch: 'out/<job description>/qdem-'.",
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
        self._seenLoad = None  # the world's last qdem.loadState this recorder followed (restart._markLoaded)
        self._claimed = False  # its .pvd checked against the other recorders' (_claimPvd)
        self.qdemId = qdemId or lifecycle.newId()
        self.command = "import qdem.yade.recorder; qdem.yade.recorder._record('%s')" % self.qdemId

    def _worldReplaced(self, old, new):
        """O.reset() replaced the default world: the new scene's frames start a new collection."""
        self.frames = []
        self._last = None
        self._seenLoad = None
        self._claimed = False

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
        """The recorder O.load puts back: its settings, frames and the step of
        its last frame, so the series goes on where the saved scene stood
        (frames the run wrote after O.save are dropped from the .pvd at the
        next frame: the loaded run writes them again)."""
        r = cls(qdemId=qdemId, **st["settings"])
        r.label, r.dead = st.get("label", ""), st.get("dead", False)
        r.frames = [tuple(f) for f in st.get("frames", [])]
        r._last = tuple(st["last"]) if st.get("last") else None
        return r

    # -- following the world's clock -------------------------------------

    def _frameStep(self, name):
        """The step in a frame's file name (fileBase NNNNNN .vtu), or None for
        a name of another fileBase."""
        prefix = os.path.basename(self._base())
        if name.startswith(prefix) and name.endswith(".vtu") and name[len(prefix):-4].isdigit():
            return int(name[len(prefix):-4])
        return None

    def _framesUpTo(self, frames, step, time, inclusive):
        """The frames before `step` (at it too when inclusive), by the step in
        their file names, else by their time."""
        def keep(f):
            n = self._frameStep(f[1])
            if n is not None:
                return n <= step if inclusive else n < step
            return f[0] <= time if inclusive else f[0] < time
        return [f for f in frames if keep(f)]

    def _earlierFrames(self):
        """The frames the .pvd on disk lists whose .vtu is still there: what
        the run before a restart wrote."""
        path = self.pvdPath()
        if not os.path.exists(path):
            return []
        try:
            root = ElementTree.parse(path).getroot()
            rows = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
        except (ElementTree.ParseError, OSError, TypeError, ValueError) as e:
            warnings.warn("VtkRecorder: cannot read the frames the earlier run listed in %s (%s): the series "
                          "starts again with this run's frames" % (path, e), RuntimeWarning, stacklevel=2)
            return []
        d = os.path.dirname(path)
        return sorted((t, f) for t, f in rows if f and os.path.exists(os.path.join(d, f)))

    def _sync(self, core):
        """Follow a world whose state was loaded (qdem.loadState: restart._markLoaded):
        keep the frames up to the step loaded - from the .pvd when this
        recorder lists none (a restart in a new process), its own (or those the
        script gave it) otherwise - and time the next frame from the
        step loaded.  A frame is then due at the next step of the period grid
        (YADE's PyRunner skips its first call: written at that call, the first
        frame of a restart fell two steps off the grid).  The step loaded is
        the same on every MPI rank, so they keep writing at the same steps."""
        mark = getattr(self.world, "_stateLoaded", None)
        if mark is not None and mark[2] != self._seenLoad:
            self._seenLoad = mark[2]
            step, time = mark[0], mark[1]
            if self._last is None and not self.frames:  # (frames a script restored itself are kept)
                self.frames = self._earlierFrames()
            self.frames = self._framesUpTo(self.frames, step, time, inclusive=True)
            self._last = (step, time)
        elif self._last is not None and core.iter < self._last[0]:
            # rewound some other way (the core's own loadState): the frames past it are written again
            self.frames = self._framesUpTo(self.frames, core.iter, core.time, inclusive=False)
            last = self._frameStep(self.frames[-1][1]) if self.frames else None
            self._last = (last, self.frames[-1][0]) if last is not None else None

    def due(self):
        """Is a frame due for the world's present state?  (Follows a
        qdem.loadState first: _sync.)"""
        core = self.world.core
        self._sync(core)
        if self._last is None:
            return True
        if core.iter == self._last[0]:
            return False
        if self.iterPeriod and core.iter % int(self.iterPeriod) == 0:
            return True
        if self.virtPeriod and math.floor(core.time / self.virtPeriod) > math.floor(self._last[1] / self.virtPeriod):
            return True
        return False

    # -- writing -------------------------------------------------------------

    def _base(self):
        """fileBase as written: an existing directory named without a trailing
        '/' ('out/run') is that directory, not a prefix of files beside it."""
        fb = self.fileBase
        if not fb.endswith(os.sep) and os.path.isdir(fb):
            return fb + os.sep
        return fb

    def _claimPvd(self):
        """Refuse a second live recorder writing this one's .pvd: each would
        rewrite the collection with its own frames only, silently."""
        mine = os.path.realpath(self.pvdPath())
        for e in O.engines:
            if isinstance(e, VtkRecorder) and e is not self and not e.dead \
                    and os.path.realpath(e.pvdPath()) == mine:
                stem = os.path.splitext(self.pvdPath())[0]
                raise SetupError("VtkRecorder(fileBase=%r) and VtkRecorder(fileBase=%r), both in O.engines, "
                                 "write the same ParaView collection %s (the .pvd name drops a trailing '-', "
                                 "'_' or '.'): each would overwrite the other's series. Give each recorder "
                                 "its own fileBase, e.g. fileBase=%r for one of them."
                                 % (self.fileBase, e.fileBase, self.pvdPath(), stem + "2-"))
        self._claimed = True

    def record(self):
        """Write one frame now (under MPI: rank 0 writes, every rank keeps the list)."""
        core = self.world.core
        self._sync(core)
        if not self._claimed:
            self._claimPvd()
        base = self._base()
        path = "%s%06d.vtu" % (base, core.iter)
        if core.mpiSize > 1 and not core.stateCurrent:
            core.gatherAll()  # collective: every rank records at the same steps
        if parallel.isWriter():
            d = os.path.dirname(base)
            try:
                if d:
                    os.makedirs(d, exist_ok=True)
                writeFrame(self.world, path)
            except OSError as e:  # a file where the directory should be, no permission, disk full
                raise type(e)(e.errno, "VtkRecorder: cannot write the frame %s (fileBase=%r): %s; choose a "
                                       "fileBase in a directory you can write to"
                              % (path, self.fileBase, e.strerror or e)) from None
        # Frames at or past this step were written by a run this one rewinds: it writes them again.
        self.frames = self._framesUpTo(self.frames, core.iter, core.time, inclusive=False)
        self.frames.append((core.time, os.path.basename(path)))
        self._last = (core.iter, core.time)
        if parallel.isWriter():
            writePvd(self.pvdPath(), self.frames)

    def pvdPath(self):
        """The ParaView collection: fileBase + '.pvd' (trailing '-', '_' or '.'
        dropped; in the directory for a directory fileBase: out/run/frames.pvd)."""
        fb = self._base()
        base = fb[:-1] if fb.endswith((".", "-", "_")) else fb
        if not os.path.basename(base):  # a directory: out/run/ -> out/run/frames.pvd, not a hidden out/run/.pvd
            base = os.path.join(base, "frames")
        return base + ".pvd"


def initialFrames(world):
    """Called by QdemEngine before the world's first step: every recorder of the
    world that has no frame yet writes the initial state (step 0, t = 0).  The
    world's clock starts here, so an old .pvd of the same fileBase (a run
    before) is replaced, not continued."""
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
