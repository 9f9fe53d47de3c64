"""The QDEM world of a scene and ``addPiece``."""
import math
import warnings

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
        """Index of a QdemMat in the compiled world, adding it on first use."""
        key = id(mat)
        if key not in self._materialIndex:
            self._materialIndex[key] = (mat, self.core.addMaterial(**mat.coreArgs()))
            mat._inUse = True  # later edits are refused (QdemMat.__setattr__)
        return self._materialIndex[key][1]

    def addPiece(self, mesh, material=None, pos=(0, 0, 0), ori=None, vel=(0, 0, 0), angVel=(0, 0, 0),
                 reorder=True, targetDt=None, maxAddedMass=0.01, regionMaterials=None):
        """Add a deformable piece: ``mesh`` (Mesh, (nodes, tets) or file) is placed
        with its origin at ``pos`` and rotated by ``ori``; it starts with rigid
        velocity ``vel`` + ``angVel`` x (x - pos).  Returns a Piece.

        ``regionMaterials`` ({region label: QdemMat}) makes one bonded piece of
        several materials (doc/meshes.md, "Regions and bimaterial parts"): each
        element takes the material of its label in ``mesh.regions`` (gmsh
        physical groups, medit references), labels not listed take
        ``material``.  Its elements, masses, viscosity and stable step are each
        element's own; its surface contacts take one material, the softest
        (smallest young) of those whose elements reach the surface - their
        radius, friction and restitution too - and ``Piece.material`` is that
        one.  All its materials must share one ``radius``.  Not with
        ``targetDt``.

        ``targetDt`` [s] turns on selective mass scaling (doc/meshes.md,
        "Selective mass scaling"): the elements whose own stable step (elastic,
        and with the material's viscosity) is below ``targetDt`` - slivers - get
        just the mass that brings it to ``targetDt``, a quarter to each of their
        nodes, so that ``stableDt()``'s elastic and viscous steps of this piece
        are at least ``targetDt``.  The added mass is real mass: gravity, contacts
        and momentum see it.  It is reported as ``Piece.addedMass``,
        ``Piece.addedMassFraction`` and ``Piece.addedMassMaxNodeShare``, and the
        piece is refused (ValueError) when ``addedMass`` exceeds ``maxAddedMass``
        times the piece's own mass (rho V).  Contact limits are not raised by it:
        a RuntimeWarning says so when ``targetDt`` is above them, and when mass
        lands on surface nodes (their contacts see the heavier nodes)."""
        # Every argument is checked before anything is added: a refused call
        # leaves the world (and the material) as they were.
        mesh = asMesh(mesh)
        if material is not None and not isinstance(material, QdemMat):
            raise ValueError("addPiece: material must be a qdem.QdemMat, got %r" % type(material).__name__)
        tetMats, regionMats = _regionMaterials(mesh, material, regionMaterials)
        if tetMats is not None and targetDt is not None:
            raise ValueError("addPiece: targetDt (selective mass scaling) is not available for a piece of several "
                             "materials (regionMaterials); remove its slivers with qdem.improveMesh(mesh) instead")
        if tetMats is not None:
            material = _contactMaterial(mesh.tets, tetMats)
        elif regionMats is not None:  # every region of one material: an ordinary piece
            material = regionMats[int(mesh.regions[0])] if len(mesh.tets) else material
        material = material if material is not None else QdemMat()
        R = rotationMatrix(ori)
        pos = _finiteVector("addPiece", "pos", pos)
        vel = _finiteVector("addPiece", "vel", vel)
        angVel = _finiteVector("addPiece", "angVel", angVel)
        if targetDt is not None:
            targetDt = _finiteNumber("addPiece", "targetDt", targetDt)
            if not targetDt > 0:
                raise ValueError("addPiece: targetDt=%r must be a positive step in seconds (or None: no mass "
                                 "scaling)" % targetDt)
        maxAddedMass = _finiteNumber("addPiece", "maxAddedMass", maxAddedMass)
        if not maxAddedMass >= 0:
            raise ValueError("addPiece: maxAddedMass=%r must be >= 0 (a fraction of the piece's mass: 0.01 is "
                             "1 %%)" % maxAddedMass)
        nodes, tets = mesh.nodes, mesh.tets
        oldOf = np.arange(len(nodes), dtype=np.int32)
        tetOldOf = None  # the mesh's own tet numbering (stableDt names its elements so)
        if reorder:
            nodes, tets, oldOf, tetOldOf = _core.hilbertReorder(nodes, tets, tetOrder=True)
        if tetMats is not None:
            # Elements of one material together (curve order kept within each):
            # the element phase computes blocks of one material.
            mine = tetMats if tetOldOf is None else [tetMats[t] for t in tetOldOf]
            rank = {id(m): k for k, m in enumerate(_distinct(tetMats))}
            order = np.argsort(np.array([rank[id(m)] for m in mine]), kind="stable")
            tets = np.asarray(tets)[order]
            tetOldOf = order if tetOldOf is None else np.asarray(tetOldOf)[order]
            tetMats = [tetMats[t] for t in tetOldOf]
        x = nodes @ R.T + pos
        if not np.all(np.isfinite(x)):
            raise ValueError("addPiece: pos/ori give non-finite node coordinates")
        v = vel + np.cross(angVel, x - pos)
        used = [material] + ([] if tetMats is None else _distinct(tetMats))
        new = [m for m in _distinct(used) if id(m) not in self._materialIndex]
        wasInUse = [m.__dict__.get("_inUse", False) for m in new]
        try:
            index = self.materialIndex(material)
            perTet = [] if tetMats is None else [self.materialIndex(m) for m in tetMats]
            added = []
            if targetDt is not None:
                added = self.core.massScaling(x, tets, index, targetDt)
                _refuseTooMuchMass(x, tets, material, added, targetDt, maxAddedMass)
            pid = self.core.addPiece(x, tets, index, added, perTet)
        except BaseException:
            # The materials registered for this piece alone: forgotten, last first.
            for m, was in reversed(list(zip(new, wasInUse))):
                if id(m) in self._materialIndex:
                    del self._materialIndex[id(m)]
                    self.core.removeLastMaterial()
                m._inUse = was
            raise
        p = Piece(self, pid, material, mesh.originalIds(oldOf))  # file point indices for a loaded mesh
        p._regionMaterials = regionMats if tetMats is not None else None
        p.vel[:] = v
        p.targetDt = targetDt
        self.pieces.append(p)
        if targetDt is not None:
            _warnMassScaling(self.core, p, targetDt)
        if tetOldOf is not None:
            self.core.setTetIds(pid, tetOldOf)
        # What the mesh's shape and size say (doc/meshes.md, "What the checks say").
        meshchecks.warnSlivers(self, pid, x, tets, index if tetMats is None and targetDt is None else None,
                               material.density)
        p._unitsNote = meshchecks.warnUnits(self, pid, x, tets, material)
        if not p._unitsNote[0]:  # (a mesh in millimetres is named as such, not as a small radius)
            meshchecks.warnRadius(pid, x, tets, material)
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


def _distinct(mats):
    """The QdemMats of a list, each once, in order of first appearance."""
    seen, out = set(), []
    for m in mats:
        if id(m) not in seen:
            seen.add(id(m))
            out.append(m)
    return out


def _regionMaterials(mesh, material, regionMaterials):
    """(per-tet QdemMat list or None, {label: QdemMat} or None) of
    addPiece's regionMaterials: None, None without it; the list is None too
    when every element has the same material (an ordinary piece)."""
    if regionMaterials is None:
        return None, None
    if not isinstance(regionMaterials, dict):
        raise ValueError("addPiece: regionMaterials must be a dict {region label: QdemMat}, got %r"
                         % type(regionMaterials).__name__)
    if mesh.regions is None:
        raise ValueError("addPiece: regionMaterials given, but the mesh has no regions (Mesh.regions is None): "
                         "regions come from gmsh physical groups or medit references (qdem.loadMesh), a CAD file "
                         "(qdem.meshCad), or Mesh(nodes, tets, regions=labels)")
    labels = sorted(int(k) for k in np.unique(mesh.regions))
    mats = {}
    for k, m in regionMaterials.items():
        if not isinstance(m, QdemMat):
            raise ValueError("addPiece: regionMaterials[%r] must be a qdem.QdemMat, got %r" % (k, type(m).__name__))
        if int(k) not in labels:
            raise ValueError("addPiece: regionMaterials names region %r, which the mesh does not have (its regions: "
                             "%s)" % (k, ", ".join(map(str, labels))))
        mats[int(k)] = m
    missing = [k for k in labels if k not in mats]
    if missing and material is None:
        raise ValueError("addPiece: regions %s have no material: list them in regionMaterials, or give material= "
                         "for the regions not listed" % ", ".join(map(str, missing)))
    for k in missing:
        mats[k] = material
    radii = {float(m.radius) for m in mats.values()}
    if len(radii) > 1:
        raise ValueError("addPiece: the materials of one bonded piece must share one contact radius (the surface "
                         "particles' reach), got %s for regions %s: give every QdemMat the same radius"
                         % (", ".join("%g m" % mats[k].radius for k in labels), ", ".join(map(str, labels))))
    perTet = [mats[int(k)] for k in mesh.regions]
    if len(_distinct(perTet)) == 1:
        return None, mats
    return perTet, mats


def _contactMaterial(tets, tetMats):
    """The contact material of a bonded piece: the softest (smallest young;
    the first such in region order on a tie) of the materials whose elements
    have a face on the surface."""
    t = np.sort(np.asarray(tets), axis=1)
    faces = np.concatenate([t[:, [1, 2, 3]], t[:, [0, 2, 3]], t[:, [0, 1, 3]], t[:, [0, 1, 2]]])
    owner = np.tile(np.arange(len(t)), 4)
    _, inverse, counts = np.unique(faces, axis=0, return_inverse=True, return_counts=True)
    outer = np.unique(owner[counts[inverse.ravel()] == 1])
    onSurface = _distinct([tetMats[e] for e in outer])
    return min(onSurface, key=lambda m: m.young)


def _tetVolumes(x, tets):
    t = np.asarray(tets)
    a, b, c, d = (x[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def _refuseTooMuchMass(x, tets, material, added, targetDt, maxAddedMass):
    """ValueError naming the figures and the remedies when selective mass
    scaling would add more than maxAddedMass of the piece's own mass."""
    added = np.asarray(added)
    if not added.size or not added.any():
        return
    own = material.density * _tetVolumes(x, tets)
    total, physical = float(added.sum()), float(own.sum())
    if total <= maxAddedMass * physical:
        return
    # The slivers' own step: M_e = rho V + added meets the target, so the
    # element's unscaled omega^2 is (M_e / rho V) times the target's.
    beta = material.viscosity / (material.young / (2 * (1 + material.poisson)))
    omega = 2.0 / math.sqrt(targetDt * (targetDt + 2 * beta))
    w0 = omega * math.sqrt(float(((own + added) / own).max()))
    xi = 0.5 * beta * w0
    dt0 = 2.0 / w0 * (math.sqrt(1 + xi * xi) - xi)
    n = int(np.count_nonzero(added))
    raise ValueError(
        "addPiece: selective mass scaling to targetDt=%.3g s would add %.4g kg, %.3g %% of the piece's %.4g kg, "
        "above maxAddedMass=%.3g %%: %d of %d elements are below targetDt, the worst allows %.3g s (a factor %.3g "
        "below). Remedies: remove the slivers with mesh = qdem.improveMesh(mesh) (no added mass; doc/meshes.md), "
        "accept more added mass with a larger maxAddedMass (it slows the piece's waves and its fall is unchanged, "
        "but its dynamics are those of a heavier body: doc/accuracy.md), or ask a smaller targetDt."
        % (targetDt, total, 100 * total / physical, physical, 100 * maxAddedMass, n, len(added), dt0,
           targetDt / dt0))


def _warnMassScaling(core, piece, targetDt):
    """RuntimeWarnings for what mass scaling does not do: raise the contact
    springs' step, or leave the surface's contact dynamics as they were."""
    info = core.pieceMassScaling(piece.id)
    if info["surfaceMass"] > 0:
        warnings.warn(
            "addPiece: selective mass scaling put %.3g kg (of %.3g kg added) on surface nodes of piece %d: their "
            "contacts see heavier nodes (a node's contact frequency goes as 1/sqrt(mass), its impact lasts longer). "
            "qdem.improveMesh(mesh) removes the slivers instead." % (info["surfaceMass"], info["addedMass"],
                                                                     piece.id),
            RuntimeWarning, stacklevel=3)
    contact, combined = core.rigidContactLimit(piece.id)
    if targetDt > contact:
        warnings.warn(
            "addPiece: targetDt=%.3g s is above the step piece %d's contact springs allow against a rigid wall "
            "(%.3g s; with its elements on the same node %.3g s), which no mass on the slivers raises: the run's "
            "step stays below that. Ask targetDt <= %.3g s, or soften the contacts (a smaller QdemMat radius or "
            "young)." % (targetDt, piece.id, contact, combined, contact),
            RuntimeWarning, stacklevel=3)


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
             world=None, targetDt=None, maxAddedMass=0.01, regionMaterials=None):
    """Add a deformable piece to the default world; see World.addPiece
    (``targetDt``, ``maxAddedMass``: selective mass scaling; ``regionMaterials``:
    one bonded piece of several materials, {region label: QdemMat})."""
    return (world or defaultWorld()).addPiece(mesh, material, pos, ori, vel, angVel, reorder, targetDt=targetDt,
                                              maxAddedMass=maxAddedMass, regionMaterials=regionMaterials)


def stableDt(world=None):
    """Stable time step of the default world (dict, see World.stableDt)."""
    return (world or defaultWorld()).stableDt()
