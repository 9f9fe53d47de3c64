"""CAD parts (STEP, IGES, BREP) meshed into linear tetrahedra with gmsh's
Python API and its OpenCASCADE kernel (Debian's python3-gmsh).  gmsh is
imported only when a CAD file is meshed."""
import contextlib
import math
import os
import signal
import sys
import tempfile
import warnings

import numpy as np

from .. import _core
from ..mesh import Mesh

# File kinds by extension: those that carry their length unit (OpenCASCADE
# converts them to metres on import) and BREP, which holds bare numbers.
_UNIT_KINDS = {".step": "STEP", ".stp": "STEP", ".iges": "IGES", ".igs": "IGES"}
_BARE_KINDS = {".brep": "BREP", ".brp": "BREP"}

# A mesh whose volume differs from the CAD solid's by more than this is named
# in a warning: curved faces cut by chords lose (or, for holes, add) volume,
# hence mass.
_VOLUME_WARN = 0.02

# Refuse a cellSize that would ask for more tetrahedra than this (estimated
# from the CAD volume): gmsh would run for hours or exhaust memory.
_MAX_TETS = 2.0e7


def _importGmsh():
    """gmsh, imported lazily.  Importing gmsh (4.8) sets SIGINT to the
    default action (Ctrl-C would kill YADE instead of raising
    KeyboardInterrupt); the handler in force is put back."""
    handler = signal.getsignal(signal.SIGINT)
    try:
        import gmsh
    except ImportError as e:
        raise RuntimeError("meshCad needs gmsh's Python API, which is not installed (%s): install it with "
                           "apt-get install python3-gmsh (Debian, for /usr/bin/python3, YADE's Python)" % e) from None
    finally:
        if handler is not None:
            signal.signal(signal.SIGINT, handler)
    return gmsh


@contextlib.contextmanager
def _quietFds():
    """Send what C++ code writes to stdout/stderr (OpenCASCADE's STEP reader
    prints its transfer statistics whatever gmsh's General.Terminal says) to
    a temporary file; yields a function returning what was written."""
    log = tempfile.TemporaryFile(mode="w+b")
    for s in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            s.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)

        def said():
            log.flush()
            log.seek(0)
            text = log.read().decode("utf-8", "replace")
            log.seek(0, os.SEEK_END)
            return text

        yield said
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
        log.close()


def _gmshIsInitialized(gmsh):
    """Whether the caller's script already runs a gmsh session (gmsh 4.8 has
    no isInitialized: model.list() is [] before the first initialize, raises
    after finalize, and lists at least one model in between)."""
    try:
        return bool(gmsh.model.list())
    except Exception:
        return False


# Options meshCad sets; restored when it borrows a session the caller opened.
_NUMBER_OPTIONS = ("General.Terminal", "General.Verbosity", "Mesh.MeshSizeMax", "Mesh.MeshSizeMin",
                   "Mesh.MeshSizeFromCurvature", "Mesh.ElementOrder", "Mesh.Optimize", "Mesh.OptimizeNetgen",
                   "Mesh.SaveAll", "Geometry.OCCScaling")
_STRING_OPTIONS = ("Geometry.OCCTargetUnit",)


@contextlib.contextmanager
def _gmshSession(gmsh):
    """A gmsh model of our own: initialized and finalized here, or, when the
    caller's script already has a session open, a model added to it and
    removed again with the options put back.  Terminal output goes to the
    log that the body can read (for error messages)."""
    handler = signal.getsignal(signal.SIGINT)
    with _quietFds() as said:
        own = not _gmshIsInitialized(gmsh)
        saved = {}
        previous = None
        if own:
            gmsh.initialize([], False)  # no user configuration files: the same mesh on every machine
        else:
            with contextlib.suppress(Exception):
                previous = gmsh.model.getCurrent()
            for o in _NUMBER_OPTIONS:
                saved[o] = (gmsh.option.setNumber, gmsh.option.getNumber(o))
            for o in _STRING_OPTIONS:
                saved[o] = (gmsh.option.setString, gmsh.option.getString(o))
        try:
            gmsh.option.setNumber("General.Terminal", 1)  # into the log file, for the error messages
            gmsh.option.setNumber("General.Verbosity", 2)  # errors and warnings only
            gmsh.model.add("qdem.meshCad")
            yield said
        finally:
            try:
                if own:
                    gmsh.finalize()
                else:
                    with contextlib.suppress(Exception):
                        gmsh.model.remove()
                    if previous:
                        with contextlib.suppress(Exception):
                            gmsh.model.setCurrent(previous)
                    for o, (setter, value) in saved.items():
                        with contextlib.suppress(Exception):
                            setter(o, value)
            finally:
                if handler is not None:
                    signal.signal(signal.SIGINT, handler)  # gmsh.finalize restores the one of its import


def _lastLines(text, n=6):
    """The last n non-empty lines of gmsh's log, for an error message."""
    lines = [l.strip() for l in text.splitlines() if l.strip() and not l.strip().startswith("*")]
    return " | ".join(lines[-n:])


def _positive(x, name):
    try:
        v = float(x)
    except (TypeError, ValueError):
        v = float("nan")
    if isinstance(x, bool) or not (math.isfinite(v) and v > 0):
        raise ValueError("meshCad: %s must be a finite number > 0 [m], got %r" % (name, x))
    return v


def _netgenOptimize(gmsh, said):
    """Netgen's tetrahedron optimiser where gmsh was built with Netgen.
    Debian's gmsh 4.8 is not ("Netgen optimizer is not compiled in this
    version of Gmsh"): the mesh is then the one gmsh's own optimiser
    (Mesh.Optimize, run by generate) left, which on the test plate lifts the
    worst height / longest edge from 0.013 to 0.15 (median 0.46)."""
    try:
        gmsh.model.mesh.optimize("Netgen")
    except Exception:
        if "not compiled" not in said():
            raise


def meshCad(path, cellSize, scale=None, minSize=None, curvature=24, optimize=True):
    """Tetrahedral mesh (linear tets, in metres) of the solid(s) of a CAD file,
    with gmsh's Python API and its OpenCASCADE kernel (Debian's
    ``python3-gmsh``).

    path: a STEP (.step/.stp), IGES (.iges/.igs) or BREP (.brep/.brp) file.
    STEP and IGES carry their length unit, and the part is converted to
    metres on import (a part drawn in millimetres comes out in metres).
    BREP holds bare numbers: ``scale`` is required (0.001 for a file in mm).
    scale (STEP/IGES): multiplies the coordinates after the conversion to
    metres (default 1; e.g. for a model drawn at 1:10).
    cellSize: the target element edge [m] (gmsh's Mesh.MeshSizeMax: the
    median edge comes out somewhat below it, single edges up to about twice
    it).  minSize: the smallest [m] (default none).  curvature: elements per full turn of a curved face or
    edge (gmsh's Mesh.MeshSizeFromCurvature; 0 turns it off): curved faces
    are cut by chords, and a cylinder cut into n sides keeps a fraction
    sin(2 pi/n) n/(2 pi) of its cross-section, 1.1 % short at n = 24.
    optimize: run gmsh's tetrahedron optimiser (Mesh.Optimize), then Netgen's
    (gmsh.model.mesh.optimize("Netgen")) where gmsh was built with it
    (Debian's gmsh 4.8 is not): they remove the slivers (near-flat tets,
    which would set a tiny stable step) that Delaunay meshing leaves.

    A file with several solids is meshed conformally (gmsh fragments them:
    solids that touch share their interface nodes) and ``Mesh.regions`` holds
    each tetrahedron's solid (its CAD volume tag), for a bimaterial part
    (``qdem.splitMesh(mesh, by='region')``).  Solids that do not touch come
    out as separate parts (``qdem.splitMesh(mesh)``).

    The mesh's volume is compared with the CAD solid's: a difference of more
    than 2 % (coarse chords on curved faces) is warned about, naming the fix.
    gmsh is started and stopped within the call (or, when the calling script
    has a gmsh session open, a model of its own is added to it and removed),
    and its terminal output is kept out of the console."""
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError("meshCad: path must be a file name (STEP, IGES or BREP), got %r" % type(path).__name__)
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    kind = _UNIT_KINDS.get(ext) or _BARE_KINDS.get(ext)
    if kind is None:
        hint = (" (a tetrahedral mesh: use qdem.loadMesh)" if ext in (".msh", ".mesh", ".vtu", ".vtk", ".ele", ".node")
                else " (a triangle surface: use qdem.meshSurface)" if ext in (".stl", ".off", ".obj", ".ply")
                else "")
        raise ValueError("meshCad: %s is not a CAD file by its extension %r%s: meshCad reads STEP (.step, .stp), "
                         "IGES (.iges, .igs) and BREP (.brep, .brp)" % (path, ext, hint))
    if not os.path.isfile(path):
        raise ValueError("meshCad: no such file: %s" % path)
    cellSize = _positive(cellSize, "cellSize")
    minSize = None if minSize is None else _positive(minSize, "minSize")
    if minSize is not None and minSize > cellSize:
        raise ValueError("meshCad: minSize %g m is larger than cellSize %g m" % (minSize, cellSize))
    if kind == "BREP" and scale is None:
        raise ValueError("meshCad: %s is a BREP file, which stores bare numbers without a length unit: give "
                         "scale, the length of one of its units in metres (scale=0.001 for millimetres, the "
                         "usual CAD unit; scale=1 for metres), or export the part as STEP, which carries its "
                         "unit" % path)
    scale = 1.0 if scale is None else _positive(scale, "scale")
    try:
        curvature = float(curvature)
    except (TypeError, ValueError):
        curvature = float("nan")
    if not (math.isfinite(curvature) and (curvature == 0 or curvature >= 3)):
        raise ValueError("meshCad: curvature (elements per full turn of a curved face) must be 0 (off) or >= 3, "
                         "got %r" % (curvature,))

    gmsh = _importGmsh()
    with _gmshSession(gmsh) as said:
        occ = gmsh.model.occ
        if kind != "BREP":
            # OpenCASCADE reads the file's unit and converts to its "cascade
            # unit", a process-wide setting that gmsh sets from this option
            # and never resets.  Millimetres is OpenCASCADE's own default, so
            # asking for it leaves the process as it was (asking for metres
            # made the next STEP file gmsh wrote in the same process read
            # back 1000 times too large).
            gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
        factor = scale * (0.001 if kind != "BREP" else 1.0)  # metres per model unit
        try:
            occ.importShapes(path)
            occ.synchronize()
        except Exception as e:
            raise ValueError("meshCad: cannot read %s as %s: %s" % (path, kind, _lastLines(said()) or e)) from None
        volumes = gmsh.model.getEntities(3)
        if not volumes:
            faces = len(gmsh.model.getEntities(2))
            raise ValueError("meshCad: %s holds no solid (%d face%s, no closed volume): a piece needs a solid. "
                             "Export the part as a solid body; a closed set of faces can be sewn into one in the "
                             "CAD program, or its surface triangulated (STL) and filled with qdem.meshSurface"
                             % (path, faces, "" if faces == 1 else "s"))
        if len(volumes) > 1:
            # Touching solids get shared interfaces (conformal nodes); overlapping ones are cut into pieces.
            occ.removeAllDuplicates()
            occ.synchronize()
            volumes = gmsh.model.getEntities(3)
        cadVolume = sum(occ.getMass(d, t) for d, t in volumes) * factor**3
        estimate = cadVolume / (cellSize**3 / (6.0 * math.sqrt(2.0))) * 2.0  # regular tets of edge cellSize, x2
        if estimate > _MAX_TETS:
            raise ValueError("meshCad: cellSize %g m on a part of %.3g m^3 would give about %.2g tetrahedra "
                             "(more than %.0g): check the unit (the part's bounding box is %s m) or use a larger "
                             "cellSize" % (cellSize, cadVolume, estimate, _MAX_TETS,
                                           " x ".join("%.3g" % (factor * (b - a)) for a, b in
                                                      zip(gmsh.model.getBoundingBox(-1, -1)[:3],
                                                          gmsh.model.getBoundingBox(-1, -1)[3:]))))
        gmsh.option.setNumber("Mesh.MeshSizeMax", cellSize / factor)
        gmsh.option.setNumber("Mesh.MeshSizeMin", (minSize or 0.0) / factor)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.option.setNumber("Mesh.Optimize", 1 if optimize else 0)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as e:
            raise ValueError("meshCad: gmsh could not mesh %s at cellSize %g m: %s. Try another cellSize, or "
                             "repair the part in the CAD program (gaps, self-intersections)"
                             % (path, cellSize, _lastLines(said()) or e)) from None
        if optimize:
            _netgenOptimize(gmsh, said)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        blocks, regions = [], []
        for d, v in volumes:
            types, _, conn = gmsh.model.mesh.getElements(d, v)
            for t, c in zip(types, conn):
                if t != 4:  # 4: the 4-node tetrahedron
                    raise ValueError("meshCad: gmsh gave elements of type %d in volume %d of %s, not linear "
                                     "tetrahedra" % (t, v, path))
                blocks.append(np.asarray(c, dtype=np.int64).reshape(-1, 4))
                regions.append(np.full(len(blocks[-1]), v, dtype=np.int64))
    if not blocks or not sum(len(b) for b in blocks):
        raise ValueError("meshCad: gmsh made no tetrahedra of %s at cellSize %g m" % (path, cellSize))
    tags = np.asarray(tags, dtype=np.int64)
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags] = np.arange(len(tags))
    tets = index[np.concatenate(blocks)]
    used = np.unique(tets)  # nodes on curves and points of the geometry belong to tets too; drop any other
    remap = np.full(len(tags), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    nodes = np.asarray(coords, dtype=float).reshape(-1, 3)[used] * factor
    tets = remap[tets].astype(np.int32)
    tets, _ = _core.orientPositive(nodes, tets)
    mesh = Mesh(nodes, tets, regions=np.concatenate(regions))
    meshVolume = float(np.sum(mesh.volumes()))
    if cadVolume > 0 and abs(meshVolume / cadVolume - 1.0) > _VOLUME_WARN:
        warnings.warn("meshCad: the mesh of %s holds %.4g m^3 against the CAD solid's %.4g m^3 (%+.1f %%), so its "
                      "mass is off by as much: curved faces are cut by too few chords. Raise curvature (now %g "
                      "elements per turn) or lower cellSize"
                      % (path, meshVolume, cadVolume, 100.0 * (meshVolume / cadVolume - 1.0), curvature),
                      stacklevel=2)
    return mesh
