"""The QDEM world of a scene and ``addPiece``."""
import math

import numpy as np

from . import _core, meshchecks
from .material import QdemMat
from .mesh import asMesh
from .piece import Piece


def _finiteVector(who, name, value, n=3, what="3 numbers (x, y, z)"):
    """``value`` as a float array of ``n`` finite numbers, else a ValueError
    naming the argument and what it must be (a Vector3, tuple, list or array)."""
    if isinstance(value, (str, bytes)) or value is None or isinstance(value, bool):
        arr = None
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            arr = None
    if arr is None or arr.shape != (n,):
        raise ValueError("%s: %s must be %s, got %r" % (who, name, what, value))
    if not np.all(np.isfinite(arr)):
        raise ValueError("%s: %s=%s is not finite" % (who, name, tuple(arr.tolist())))
    return arr


def _finiteNumber(who, name, value):
    if isinstance(value, (str, bytes, bool)) or np.ndim(value) != 0:
        raise ValueError("%s: %s must be a number, got %r" % (who, name, value))
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError("%s: %s must be a number, got %r" % (who, name, value)) from None
    if not math.isfinite(v):
        raise ValueError("%s: %s=%r is not finite" % (who, name, v))
    return v


_ORI_FORMS = "a YADE Quaternion, an (axis, angle) pair such as ((0, 0, 1), 0.5) or a proper 3x3 rotation matrix"


def rotationMatrix(ori):
    """3x3 rotation from None, a YADE Quaternion (normalised), an (axis, angle)
    pair (tuple or list; the axis need not be a unit vector) or a 3x3 rotation
    matrix (orthonormal to 1e-9, determinant +1)."""
    who = "addPiece"
    if ori is None:
        return np.eye(3)
    if hasattr(ori, "toAxisAngle"):  # YADE / minieigen Quaternion
        q = _finiteVector(who, "ori (Quaternion)", [ori[k] for k in range(4)], 4, "a finite Quaternion")
        if not np.linalg.norm(q) > 0:
            raise ValueError("%s: ori=Quaternion(0,0,0,0) is no rotation (zero norm); use Quaternion.Identity or "
                             "ori=None for none" % who)
        axis, angle = ori.normalized().toAxisAngle()
        return _axisAngle(np.array([axis[0], axis[1], axis[2]], dtype=float), float(angle))
    if isinstance(ori, (str, bytes)):
        raise ValueError("%s: ori must be %s, got %r" % (who, _ORI_FORMS, ori))
    if isinstance(ori, (tuple, list)) and len(ori) == 2:
        axisArg, angleArg = ori
        if np.ndim(axisArg) == 0 and np.ndim(angleArg) == 1:
            raise ValueError("%s: ori=(axis, angle) takes the axis first, got %r; write ori=(%r, %r)"
                             % (who, ori, angleArg, axisArg))
        axis = _finiteVector(who, "ori's axis", axisArg, 3, "3 numbers (ori=(axis, angle))")
        angle = _finiteNumber(who, "ori's angle", angleArg)
        return _axisAngle(axis, angle)
    try:
        R = np.asarray(ori, dtype=float)
    except (TypeError, ValueError):
        R = None
    if R is None or R.shape != (3, 3):
        raise ValueError("%s: ori must be %s, got %r" % (who, _ORI_FORMS, ori))
    if not np.all(np.isfinite(R)):
        raise ValueError("%s: ori: the rotation matrix is not finite" % who)
    err = float(np.abs(R @ R.T - np.eye(3)).max())
    if not err <= 1e-9:
        raise ValueError("%s: ori: the 3x3 matrix is not a rotation (R R^T differs from the identity by %.3g; "
                         "it must be orthonormal to 1e-9, no scaling)" % (who, err))
    if np.linalg.det(R) < 0:
        raise ValueError("%s: ori: the 3x3 matrix is a reflection (determinant -1), not a rotation; a mirrored "
                         "piece would be inside out" % who)
    return R


def _axisAngle(axis, angle):
    n = np.linalg.norm(axis)
    if not n > 0:
        raise ValueError("addPiece: ori's rotation axis must be non-zero")
    k = axis / n
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


class World:
    """All QDEM pieces of a scene (a thin Python owner of the compiled World)."""

    def __init__(self):
        self.core = _core.World()
        self.pieces = []
        self._materialIndex = {}  # id(QdemMat) -> (material, core index)

    def materialIndex(self, mat):
        key = id(mat)
        if key not in self._materialIndex:
            self._materialIndex[key] = (mat, self.core.addMaterial(*mat.coreArgs()))
            mat._inUse = True  # later edits are refused (QdemMat.__setattr__)
        return self._materialIndex[key][1]

    def addPiece(self, mesh, material=None, pos=(0, 0, 0), ori=None, vel=(0, 0, 0), angVel=(0, 0, 0),
                 reorder=True):
        """Add a deformable piece: ``mesh`` (Mesh, (nodes, tets) or file) is placed
        with its origin at ``pos`` and rotated by ``ori``; it starts with rigid
        velocity ``vel`` + ``angVel`` x (x - pos).  Returns a Piece."""
        # Every argument is checked before anything is added: a refused call
        # leaves the world (and the material) as they were.
        mesh = asMesh(mesh)
        material = material if material is not None else QdemMat()
        if not isinstance(material, QdemMat):
            raise ValueError("addPiece: material must be a qdem.QdemMat, got %r" % type(material).__name__)
        R = rotationMatrix(ori)
        pos = _finiteVector("addPiece", "pos", pos)
        vel = _finiteVector("addPiece", "vel", vel)
        angVel = _finiteVector("addPiece", "angVel", angVel)
        nodes, tets = mesh.nodes, mesh.tets
        oldOf = np.arange(len(nodes), dtype=np.int32)
        tetOldOf = None  # the mesh's own tet numbering (stableDt names its elements so)
        if reorder:
            nodes, tets, oldOf, tetOldOf = _core.hilbertReorder(nodes, tets, tetOrder=True)
        x = nodes @ R.T + pos
        if not np.all(np.isfinite(x)):
            raise ValueError("addPiece: pos/ori give non-finite node coordinates")
        v = vel + np.cross(angVel, x - pos)
        newMaterial = id(material) not in self._materialIndex
        wasInUse = material.__dict__.get("_inUse", False)
        index = self.materialIndex(material)
        try:
            pid = self.core.addPiece(x, tets, index)
        except BaseException:
            if newMaterial:  # the material was registered for this piece alone: forget it
                del self._materialIndex[id(material)]
                self.core.removeLastMaterial()
                material._inUse = wasInUse
            raise
        p = Piece(self, pid, material, mesh.originalIds(oldOf))  # file point indices for a loaded mesh
        p.vel[:] = v
        self.pieces.append(p)
        if tetOldOf is not None:
            self.core.setTetIds(pid, tetOldOf)
        # What the mesh's shape and size say (doc/meshes.md, "What the checks say").
        meshchecks.warnSlivers(self, pid)
        p._unitsNote = meshchecks.warnUnits(self, pid, x, tets, material)
        return p

    def stableDt(self):
        """Stable time step: dict with elastic, viscous, contact, combined [s] and limitedBy;
        combinedExplicit / combinedImplicit: combined with explicit / implicit viscosity.
        What in the element step sets it (doc/meshes.md, "What the checks say"): piece (its
        index, -1 without pieces), elements (up to 10 of its tetrahedra with the smallest
        steps, smallest first, in its mesh's numbering), elementsNearLimit (how many allow a
        step within 2x of the smallest), worstQuality (their smallest min height / longest
        edge), medianElastic / medianViscous (the steps its median element allows [s]),
        medianFactorElastic / medianFactorViscous (those over the piece's limit) and
        elementLimit (all of it in one sentence)."""
        return self.core.stableDt()


_default = None


def defaultWorld():
    """The world that ``qdem.addPiece`` and a ``QdemEngine()`` without ``world=`` use."""
    global _default
    if _default is None:
        _default = World()
    return _default


class FollowsDefaultWorld:
    """Mixin of the engines (QdemEngine, VtkRecorder): ``world`` is the world
    given as ``world=``, else the default world — the current one.  YADE
    engines act on whatever scene is current, so an engine kept across
    ``O.reset()`` (one list of engines reused for every run of a sweep) steps
    the new scene's pieces, not the emptied world's; ``_worldReplaced(old,
    new)`` carries the engine's settings over and starts its run state afresh."""

    def _setWorld(self, world):
        self._followsDefault = world is None
        self._world = world or defaultWorld()

    @property
    def world(self):
        """The qdem.World this engine acts on: the one given as world=, else
        qdem.defaultWorld() (after O.reset(), the new one)."""
        w = self._world
        if self._followsDefault and w is not _default:
            new = defaultWorld()
            self._world = new
            self._worldReplaced(w, new)
            w = new
        return w


def reset():
    """Forget all pieces (call with O.reset())."""
    global _default
    _default = None


def addPiece(mesh, material=None, pos=(0, 0, 0), ori=None, vel=(0, 0, 0), angVel=(0, 0, 0), reorder=True,
             world=None):
    """Add a deformable piece to the default world; see World.addPiece."""
    return (world or defaultWorld()).addPiece(mesh, material, pos, ori, vel, angVel, reorder)


def stableDt(world=None):
    """Stable time step of the default world (dict, see World.stableDt)."""
    return (world or defaultWorld()).stableDt()
