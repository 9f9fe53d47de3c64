"""The QDEM world of a scene and ``addPiece``."""
import math

import numpy as np

from . import _core
from .material import QdemMat
from .mesh import asMesh
from .piece import Piece


def rotationMatrix(ori):
    """3x3 rotation from None, a YADE Quaternion, an (axis, angle) pair or a 3x3 matrix."""
    if ori is None:
        return np.eye(3)
    if hasattr(ori, "toAxisAngle"):  # YADE / minieigen Quaternion
        axis, angle = ori.toAxisAngle()
        return _axisAngle(np.array([axis[0], axis[1], axis[2]], dtype=float), float(angle))
    if isinstance(ori, tuple) and len(ori) == 2 and np.ndim(ori[1]) == 0:
        return _axisAngle(np.asarray(ori[0], dtype=float), float(ori[1]))
    R = np.asarray(ori, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise ValueError("ori must be a Quaternion, (axis, angle) or a proper 3x3 rotation matrix")
    return R


def _axisAngle(axis, angle):
    n = np.linalg.norm(axis)
    if not n > 0:
        raise ValueError("ori: rotation axis must be non-zero")
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
        mesh = asMesh(mesh)
        material = material if material is not None else QdemMat()
        if not isinstance(material, QdemMat):
            raise ValueError("addPiece: material must be a qdem.QdemMat, got %r" % type(material).__name__)
        R = rotationMatrix(ori)
        pos = np.asarray(pos, dtype=float).reshape(3)
        for name, val in (("vel", vel), ("angVel", angVel)):
            if not np.all(np.isfinite(np.asarray(val, dtype=float))):
                raise ValueError("addPiece: %s=%s is not finite" % (name, tuple(np.ravel(val))))
        nodes, tets = mesh.nodes, mesh.tets
        oldOf = np.arange(len(nodes), dtype=np.int32)
        if reorder:
            nodes, tets, oldOf = _core.hilbertReorder(nodes, tets)
        x = nodes @ R.T + pos
        if not np.all(np.isfinite(x)):
            raise ValueError("addPiece: pos/ori give non-finite node coordinates")
        pid = self.core.addPiece(x, tets, self.materialIndex(material))
        p = Piece(self, pid, material, oldOf)
        v = np.asarray(vel, dtype=float).reshape(3) + np.cross(np.asarray(angVel, dtype=float).reshape(3), x - pos)
        p.vel[:] = v
        self.pieces.append(p)
        return p

    def stableDt(self):
        """Stable time step: dict with elastic, viscous, contact, combined [s] and limitedBy;
        combinedExplicit / combinedImplicit: combined with explicit / implicit viscosity."""
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
