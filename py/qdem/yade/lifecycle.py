"""QDEM inside YADE's scene life cycle: O.save / O.load (every format YADE
writes: .yade, .gz, .bz2, .xml), O.saveTmp / O.loadTmp, O.reset, and QDEM
errors reaching the script as what they are.

How (doc/yade.md): importing qdem wraps a few methods of YADE's Omega class
(the type of ``O``), calling YADE's own method inside each wrapper.

- ``O.save(f)`` / ``O.saveTmp(name)`` first write the whole QDEM scene -
  materials, meshes, the dynamic state that ``qdem.saveState`` writes, the
  settings of every QdemEngine and the frame list of every VtkRecorder - into
  ``O.tags['qdem']`` (compressed npz, base64), so it is *inside* YADE's saved
  scene: one file, which saveTmp, mpy and yade-batch carry like any scene.
- ``O.sceneToString()`` / ``O.stringToScene(s)`` (how mpy sends a scene to
  its workers) and ``O.reload()`` do the same as save and load.
- ``O.load(f)`` / ``O.loadTmp(name)`` rebuild the QDEM world from that tag,
  or empty it when the loaded scene has none, and put QdemEngine and
  VtkRecorder objects back in O.engines (YADE keeps them as plain PyRunners).
  A scene whose engines step QDEM but that carries no QDEM tag is refused
  with a message saying what to do.  A PyRunner that finds no engine object
  for its command (a scene loaded some other way) rebuilds the world and the
  engine from the same tag at its first call.
- ``O.reset()`` (and resetThisScene, resetCurrentScene, resetAllScenes) empties the QDEM world.
- A QDEM exception inside ``O.run``/``O.step``/``O.wait`` reaches the script as
  itself (``except qdem.StabilityError`` works, message intact), where YADE
  would give a generic ``RuntimeError: PyRunner error.``."""
import base64
import builtins
import functools
import io
import json
import math
import threading
import time
import uuid
import warnings
import weakref

import numpy as np
from yade import O as _O, wrapper

from .. import world as worldModule
from ..io.restart import _markLoaded
from ..material import QdemMat
from ..mpi import ranks as parallel
from ..piece import Piece

FORMAT = 1
TAG = "qdem"

# No table of engines: O.engines hands back the QdemEngine and VtkRecorder
# objects themselves (YADE keeps the Python object of a Python subclass), so
# a command finds its engine there by the id it names (qdemObject).  The
# classes saved with the scene register here (savedWithScene): this module
# sits below them (they use its ids, errors and engine lookup) and never
# imports them.
_KINDS = {}  # class name -> class, of the engines O.save keeps (QdemEngine, VtkRecorder)
_pending = []  # the QDEM exception of the step that failed, for the wrappers of O.run/O.step/O.wait


def newId():
    return uuid.uuid4().hex[:16]


def savedWithScene(cls):
    """Class decorator: `cls` (a PyRunner subclass with qdemId, savedState and
    fromSaved) is saved with the scene by O.save and rebuilt by O.load."""
    _KINDS[cls.__name__] = cls
    return cls


# ---------------------------------------------------------------------------
# The QDEM scene as one string


def _coreSettings(core):
    return {k: getattr(core, k) for k in ("verletSkin", "edgeFeatureAngle", "edgeFadeAngle")}


def sceneBlob(world, O):
    """Everything needed to rebuild `world` and the QDEM engines of O.engines, as a string."""
    core = world.core
    meta = {"format": FORMAT, "settings": _coreSettings(core), "materials": [], "pieces": [], "engines": {}}
    arrays = {}
    mats = sorted(world._materialIndex.values(), key=lambda mi: mi[1])
    for k, (mat, index) in enumerate(mats):
        if index != k:
            raise RuntimeError("qdem: material indices are not contiguous (internal error)")
        meta["materials"].append({n: getattr(mat, n) for n in QdemMat.attrNames()})
    for p in world.pieces:
        i = len(meta["pieces"])
        meta["pieces"].append({"material": world.materialIndex(p.material)})
        arrays["refPos%d" % i] = np.array(p.refPos)
        arrays["tets%d" % i] = np.array(p.tets, dtype=np.int32)
        arrays["oldOf%d" % i] = np.asarray(p.originalNodeIds, dtype=np.int32)
        arrays["addedMass%d" % i] = np.array(core.tetAddedMass[p.tetSlice])  # selective mass scaling
        meta["pieces"][-1]["targetDt"] = p.targetDt
        arrays["tetIds%d" % i] = np.asarray(core.tetIds(p.id), dtype=np.int32)
        if p.regionMaterials is not None:  # a bonded piece: each element's material, each region's
            arrays["tetMaterial%d" % i] = np.array(core.tetMaterial[p.tetSlice], dtype=np.int32)
            meta["pieces"][-1]["regionMaterials"] = {str(k): world.materialIndex(m)
                                                     for k, m in p.regionMaterials.items()}
    if core.mpiSize > 1:
        core.gatherState()  # collective: under mpiexec every rank runs O.save
    for name, data in core.saveState().items():
        arrays["state:" + name] = np.frombuffer(data, dtype=np.uint8)
    for e in O.engines:
        obj = qdemObject(e)
        if obj is not None:
            if obj.world is not world:
                raise RuntimeError("O.save: engine %r steps a qdem.World other than the default one; only the "
                                   "default world (qdem.addPiece) is saved with the scene" % obj)
            meta["engines"][obj.qdemId] = obj.savedState()
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _readBlob(blob):
    try:
        data = np.load(io.BytesIO(base64.b64decode(blob)))
        meta = json.loads(data["meta"].tobytes().decode())
    except Exception as e:  # a damaged tag: say so, never half-build a world
        raise ValueError("O.load: the scene's QDEM state (O.tags['qdem']) is damaged: %s" % e) from None
    if meta.get("format") != FORMAT:
        raise ValueError("O.load: the scene's QDEM state has format %r, this qdem reads %d"
                         % (meta.get("format"), FORMAT))
    return data, meta


def _sameWorld(w, blob):
    """Does world `w` hold the pieces (meshes, materials) the blob holds?"""
    data, meta = _readBlob(blob)
    if len(w.pieces) != len(meta["pieces"]):
        return False
    for i, p in enumerate(w.pieces):
        if not (np.array_equal(np.asarray(p.refPos), data["refPos%d" % i])
                and np.array_equal(np.asarray(p.tets, dtype=np.int32), data["tets%d" % i])
                and np.array_equal(np.asarray(p.addedMassPerTet), _addedMass(data, i, len(p.addedMassPerTet)))
                and _sameTetMaterials(w, p, data, i)):
            return False
    return True


def _sameTetMaterials(w, p, data, i):
    """Does piece p have the per-element materials (a bonded piece's) that
    the blob's piece i has?"""
    key = "tetMaterial%d" % i
    if (key in data.files) != (p.regionMaterials is not None):
        return False
    return key not in data.files or np.array_equal(np.asarray(w.core.tetMaterial[p.tetSlice]), data[key])


def savedSettings(settings):
    """Settings of a saved scene as this version takes them.  edgeFeatureAngle
    was accepted above pi before (the help said "above pi: none", but the
    angle went through a cosine): such a value is the angle it acted as,
    acos(cos(v)), with a warning, instead of a refused load."""
    out = dict(settings)
    v = out.get("edgeFeatureAngle")
    if v is not None and not 0 <= v <= math.pi and math.isfinite(v):
        out["edgeFeatureAngle"] = math.acos(math.cos(v))
        warnings.warn("qdem: the loaded scene has edgeFeatureAngle = %g, above pi (accepted before, now refused); "
                      "it acted as acos(cos(%g)) = %.6g rad, which is set. Angles are in radians." %
                      (v, v, out["edgeFeatureAngle"]), RuntimeWarning, stacklevel=3)
    return out


def _addedMass(data, i, nTets):
    """Piece i's mass added per tet (selective mass scaling): zeros for a
    scene saved before it was kept."""
    key = "addedMass%d" % i
    return np.array(data[key]) if key in data.files else np.zeros(nTets)


def restoreWorld(blob, into=None):
    """A new default world built from a sceneBlob string; returns (world, engine
    states).  With `into`, a world holding the same pieces (_sameWorld): only
    its state and settings are loaded."""
    data, meta = _readBlob(blob)
    if into is not None:
        for k, v in savedSettings(meta["settings"]).items():
            setattr(into.core, k, v)
        into.core.loadState({k[6:]: data[k].tobytes() for k in data.files if k.startswith("state:")})
        return into, meta["engines"]
    worldModule.reset()
    w = worldModule.defaultWorld()
    w._restored = True  # (an engine of the scene before does not carry its settings into it)
    mats = [QdemMat(**m) for m in meta["materials"]]
    for m in mats:
        w.materialIndex(m)
    for i, pm in enumerate(meta["pieces"]):
        mat = mats[pm["material"]]
        tets = data["tets%d" % i]
        perTet = data["tetMaterial%d" % i].tolist() if "tetMaterial%d" % i in data.files else []
        pid = w.core.addPiece(data["refPos%d" % i], tets, w.materialIndex(mat), _addedMass(data, i, len(tets)),
                              perTet)
        w.pieces.append(Piece(w, pid, mat, np.array(data["oldOf%d" % i])))
        if "regionMaterials" in pm:
            w.pieces[-1]._regionMaterials = {int(k): mats[j] for k, j in pm["regionMaterials"].items()}
            for m in w.pieces[-1]._regionMaterials.values():
                m._inUse = True
        w.pieces[-1].targetDt = pm.get("targetDt")
        if "tetIds%d" % i in data.files:  # (scenes saved before elements kept their mesh's numbering: local)
            w.core.setTetIds(pid, data["tetIds%d" % i])
        mat._inUse = True
    for k, v in savedSettings(meta["settings"]).items():
        setattr(w.core, k, v)
    w.core.loadState({k[6:]: data[k].tobytes() for k in data.files if k.startswith("state:")})
    _markLoaded(w)  # a VtkRecorder made after O.load goes on with the saved run's series
    return w, meta["engines"]


# ---------------------------------------------------------------------------
# Engines in O.engines


def _blob(O):
    """The QDEM scene string of O.tags, or None."""
    return (O.tags[TAG] or None) if O.tags.has_key(TAG) else None


def _idOf(e):
    """The qdem id in a PyRunner's command ('' for any other engine)."""
    cmd = getattr(e, "command", "")
    if not isinstance(cmd, str) or not cmd.startswith("import qdem"):
        return ""
    i = cmd.find("('")
    return cmd[i + 2:cmd.find("'", i + 2)] if i >= 0 else ""


def _rebind(O, engineStates):
    """Replace the plain PyRunners of QDEM engines in O.engines by the engine
    objects, built from their saved settings; labels follow."""
    kinds = _KINDS
    out, changed = [], False
    for e in O.engines:
        qid = _idOf(e)
        st = engineStates.get(qid) if qid else None
        if st is None or isinstance(e, tuple(kinds.values())):
            out.append(e)
            continue
        obj = kinds[st["kind"]].fromSaved(qid, st, e)
        out.append(obj)
        changed = True
    if changed:
        O.engines = out
        for obj in out:
            lab = getattr(obj, "label", "")
            if lab and _idOf(obj):
                setattr(builtins, lab, obj)  # where YADE puts labels
    return changed


def afterLoad(O, how="O.load"):
    """Bring QDEM in line with a scene YADE has just loaded (by `how`, the
    method the script called: named in the refusal of stale Piece handles)."""
    _found.clear()
    blob = _blob(O)
    qdemEngines = [e for e in O.engines if _idOf(e)]
    if blob is None:
        worldModule.reset()
        if qdemEngines:
            raise RuntimeError("O.load: this scene has QDEM engines but no QDEM state (O.tags['qdem']): it was "
                               "saved by a script that did not import qdem before O.save. Re-run the script "
                               "with 'import qdem' at its top, or rebuild the pieces and use qdem.loadState "
                               "with a file written by qdem.saveState.")
        return
    if parallel._mpyInUse() and _sameWorld(worldModule.defaultWorld(), blob):
        # yade.mpy's split: a worker receives the master's scene, whose QDEM
        # world its own script built alike.  Its state goes into that world,
        # so the script's Piece objects stay live on the worker.
        states = restoreWorld(blob, into=worldModule.defaultWorld())[1]
    else:
        old = worldModule._default
        same = old is not None and _sameWorld(old, blob)
        new, states = restoreWorld(blob)
        if same:
            # The scene loaded holds the same pieces (O.loadTmp rewinding a
            # run, O.reload): the script's Piece handles follow it, as its
            # YADE body ids do, instead of reading the scene before the load
            # and losing what is written to them.
            for i, p in enumerate(old.pieces):
                p.world, p._material = new, new.pieces[i]._material
                new.pieces[i] = p
        if old is not None:
            old._replacedBy = how if not same else None
    O.tags[TAG] = ""  # the live scene keeps no stale copy (YADE's tags cannot be deleted)
    _rebind(O, states)


def qdemObject(e):
    """e itself when it is a QdemEngine or a VtkRecorder, else None."""
    return e if isinstance(e, tuple(_KINDS.values())) else None


def _inEngines(O, qid):
    for e in O.engines:
        obj = qdemObject(e)
        if obj is not None and obj.qdemId == qid:
            return obj
    return None


_found = {}  # qid -> weakref of the engine engineFor found; emptied when O.engines is assigned or a scene loaded, reset or switched


def engineFor(qid):
    """The engine object whose PyRunner command names `qid`, found in
    O.engines; rebuilt from O.tags when a scene was loaded without qdem's
    wrappers (e.g. qdem imported after O.load).  Every QDEM step asks: the
    answer is kept (a search of O.engines cost ~15 us a step) until O.engines
    is assigned or a scene is loaded, reset or switched (install())."""
    ref = _found.get(qid)
    obj = ref() if ref is not None else None
    if obj is not None:
        return obj
    obj = _inEngines(_O, qid)
    if obj is not None:
        _found[qid] = weakref.ref(obj)
        return obj
    if _blob(_O):
        afterLoad(_O)
        obj = _inEngines(_O, qid)
        if obj is not None:
            return obj
    if parallel._mpyInUse():
        # A yade.mpy worker whose scene mpy replaced by the master's without
        # QDEM's state (O.sceneToString not wrapped: qdem imported too late).
        raise RuntimeError("qdem: a yade.mpy worker received a scene whose QdemEngine has no QDEM state: "
                           "'import qdem' at the top of the script, before building the scene and calling "
                           "mp.mpirun, on every rank (doc/parallel.md, 'Under yade.mpy')")
    raise RuntimeError("qdem: no engine for command id %s: this scene was saved without its QDEM state. "
                       "Re-run the script that built it with 'import qdem' before O.save." % qid)


# ---------------------------------------------------------------------------
# Wrapping Omega's methods


_calls = threading.local()  # _callBare: the call in progress, per thread


def _callBare():
    """Calls the innermost pending call (a functools.partial) from a frame
    with no local variables.  YADE's PyRunner (updateGlobals=True, as
    QdemEngine) copies the locals of the innermost Python frame into the
    script's globals after its command: when O.step() runs the engines in
    the script's thread, that frame was this wrapper's, and a script's
    variables named a, k, self or orig were overwritten every step (found by
    a tester).  A partial is called from C, so no frame of its own."""
    return _calls.stack[-1]()


def _wrapErrors(orig):
    def wrapped(self, *a, **k):
        if orig.__name__ != "wait":
            del _pending[:]
        stack = getattr(_calls, "stack", None)
        if stack is None:
            stack = _calls.stack = []
        stack.append(functools.partial(orig, self, *a, **k))
        try:
            r = _callBare()
        except RuntimeError as e:
            if _pending and "PyRunner error" in str(e):
                err = _pending.pop()
                del _pending[:]
                raise err.with_traceback(None) from None
            raise
        finally:
            stack.pop()
        if _pending and (orig.__name__ != "run" or (a[1:2] or [k.get("wait", False)])[0]):
            # O.step() logs an engine's error and returns: raise it here
            err = _pending.pop()
            del _pending[:]
            raise err.with_traceback(None) from None
        return r
    wrapped.__doc__ = orig.__doc__
    wrapped.__name__ = getattr(orig, "__name__", "wrapped")
    wrapped._qdemOrig = orig
    return wrapped


stepSeconds = 0.0  # wall time between the last two QDEM steps (QdemEngine._run): how long a step lasts


def _settle(O):
    """After O.pause(), YADE's O.wait() returns at once, and the loop thread
    still finishes the step it is in (O.subStep >= 0 until then; measured:
    one more step lands after O.wait()).  Saving or loading then wrote
    QDEM's part and YADE's from different steps, or crashed inside YADE's
    load.  Waits for that step, from the script's thread; bounded, since a
    step that raised leaves O.subStep >= 0 with nothing in flight."""
    if O.running or threading.current_thread() is not threading.main_thread() or O.subStep < 0:
        return
    it = O.iter
    deadline = time.monotonic() + min(60.0, max(0.05, 20 * stepSeconds))
    while O.subStep >= 0 and O.iter == it and time.monotonic() < deadline:
        time.sleep(0.0005)
    while O.subStep >= 0 and O.iter != it and time.monotonic() < deadline:  # (epilogue of the step)
        time.sleep(0.0005)


def _wrapSave(orig, toFile=True):
    def wrapped(self, *a, **k):
        _settle(self)
        w = worldModule.defaultWorld()
        qdemScene = w.pieces or any(_idOf(e) for e in self.engines)
        if qdemScene and self.running and threading.current_thread() is threading.main_thread():
            # The loop thread goes on stepping while QDEM's part is written
            # here and YADE's after it: the two would come from different
            # steps (a tester found 22 steps apart).  From a PyRunner inside
            # the run (the loop thread) the save is between steps: fine.
            raise RuntimeError("O.save: a run is going on in the background (O.running): QDEM's part and YADE's "
                               "part of the file could come from different steps. Call O.pause() and O.wait() "
                               "first (O.run() resumes), or save from a PyRunner inside the run.")
        if qdemScene:
            self.tags[TAG] = sceneBlob(w, self)
        try:
            # O.saveTmp keeps each rank's copy in its own memory.
            if not toFile:
                return orig(self, *a, **k)
            path = a[0] if a else k.get("file")

            def write():
                if isinstance(path, str):
                    parallel.checkWritable(path, "O.save")
                return orig(self, *a, **k)
            # Under mpiexec every rank runs the script: rank 0 alone writes
            # the file, and a failure there stops every rank.
            return parallel.writerDoes(write, "O.save(%r)" % (path,))
        finally:
            if _blob(self):
                self.tags[TAG] = ""
    wrapped.__doc__ = orig.__doc__
    wrapped._qdemOrig = orig
    return wrapped


def _wrapAfter(after):
    """A wrapper that calls YADE's method, then after(O, "O.<method>")."""
    def wrap(orig):
        how = "O." + getattr(orig, "__name__", "load")

        def wrapped(self, *a, **k):
            _settle(self)
            r = orig(self, *a, **k)
            after(self, how)
            return r
        wrapped.__doc__ = orig.__doc__
        wrapped._qdemOrig = orig
        return wrapped
    return wrap


def _forgetEngines(O, how=None):
    _found.clear()


def _resetWorld(O, how=None):
    _found.clear()
    worldModule.reset()


_wrapLoad = _wrapAfter(afterLoad)      # load, loadTmp: QDEM follows the loaded scene
_wrapReset = _wrapAfter(_resetWorld)   # reset, resetThisScene, resetCurrentScene: QDEM emptied too


def install():
    """Wrap Omega's methods (once per process)."""
    Omega = wrapper.Omega
    plan = {"run": _wrapErrors, "step": _wrapErrors, "wait": _wrapErrors,
            "save": _wrapSave, "saveTmp": lambda o: _wrapSave(o, toFile=False),
            "sceneToString": lambda o: _wrapSave(o, toFile=False),  # how mpy sends the scene to its workers
            "load": _wrapLoad, "loadTmp": _wrapLoad, "stringToScene": _wrapLoad,
            "reload": _wrapLoad,  # YADE's reload loads O.filename in C++, past the wrapper of load
            "reset": _wrapReset, "resetThisScene": _wrapReset, "resetCurrentScene": _wrapReset,
            "resetAllScenes": _wrapReset}
    for name, wrap in plan.items():
        orig = getattr(Omega, name, None)
        if orig is None or hasattr(orig, "_qdemOrig"):
            continue
        setattr(Omega, name, wrap(orig))
    # engineFor keeps what it found until the engines change: O.engines = ...
    # (YADE hands out a copy of the list, so assignment is the only way) or
    # another scene made current.
    prop = Omega.__dict__.get("engines")
    if isinstance(prop, property) and prop.fset is not None and not hasattr(prop.fset, "_qdemOrig"):
        def setEngines(self, value, _set=prop.fset):
            _found.clear()
            _set(self, value)
        setEngines._qdemOrig = prop.fset
        Omega.engines = property(prop.fget, setEngines, prop.fdel, prop.__doc__)
    for name in ("switchScene", "addScene"):
        orig = getattr(Omega, name, None)
        if orig is not None and not hasattr(orig, "_qdemOrig"):
            setattr(Omega, name, _wrapAfter(_forgetEngines)(orig))
