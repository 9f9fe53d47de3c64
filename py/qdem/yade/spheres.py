"""Coupling QDEM pieces with YADE's own spheres and clumps (doc/spheres.md).

Which spheres can touch a piece is YADE's collider's business: every piece
gets a *proxy* body, a non-dynamic ``Tetra`` whose bounding box is the piece's
box plus a margin.  YADE's InsertionSortCollider keeps a potential interaction
between the proxy and every body whose bound overlaps it (a sphere's bound
holds the sphere), and with no ``Ig2`` functor for Tetra-Sphere none of them
ever becomes real.  So ``O.interactions.withBodyAll(proxy)`` is, at any time,
a superset of the spheres that can touch the piece, kept up to date by the
collider at the collider's own cost.  The lists are re-read only when the
collider has run (its ``numAction`` changed) or a proxy moved; the states of
the listed spheres are read every step, and forces written back with
``O.forces`` for those in contact.  A scene whose spheres are all far away
reads nothing but one counter per step."""
import warnings

import math

import numpy as np
import yade

from .. import _core
from . import glue as yadeglue
from .glue import PROXY_LABEL as _PROXY_LABEL, looksLikeProxy  # noqa: F401  (looksLikeProxy: spheres' API)

TAN = np.tan
_PROXY_MASK_DEFAULT = -1


def _vertices(lo, hi):
    """Four alternate corners of the box [lo, hi] around its centre: a tetra
    whose axis-aligned bounding box is exactly that box."""
    h = 0.5 * (np.asarray(hi) - np.asarray(lo))
    return [(-h[0], -h[1], -h[2]), (h[0], h[1], -h[2]), (h[0], -h[1], h[2]), (-h[0], h[1], h[2])]


def sphereProperties(O, b):
    """(radius, young, ks/kn, friction, restitution, mass) of a YADE sphere body
    for the coupling law (doc/spheres.md)."""
    m = b.material
    young = float(getattr(m, "young", 0.0) or 0.0)
    if young <= 0:
        raise ValueError("QdemEngine: sphere #%d: its material %s has no positive 'young'; sphere-QDEM contacts "
                         "need FrictMat, ViscElMat or another ElastMat" % (b.id, type(m).__name__))
    ratio = float(getattr(m, "poisson", -1.0))  # YADE's FrictMat.poisson is ks/kn
    angle = getattr(m, "frictionAngle", None)
    if angle is None:
        friction = -1.0  # none: the piece's frictionPiece alone (as an obstacle's material without one)
    else:
        angle = float(angle)
        if not (0.0 <= angle < 0.5 * math.pi):
            raise ValueError("QdemEngine: sphere #%d: its material's frictionAngle = %r rad is not in [0, pi/2): "
                             "give it the angle in radians, e.g. math.atan(0.5) for a coefficient of 0.5"
                             % (b.id, angle))
        friction = float(TAN(angle))
    en = getattr(m, "en", None)  # ViscElMat: restitution coefficient
    restitution = float(en) if en is not None and 0 < en <= 1 else -1.0
    mass = b.state.mass
    if b.isClumpMember:
        mass = O.bodies[b.clumpId].state.mass
    if not b.dynamic or not mass > 0:
        mass = 1e300  # fixed (or massless) sphere: the dashpot sees only the QDEM side
    return (b.shape.radius, young, ratio, friction, restitution, mass)


def _clumpState(O, b):
    """A clump member's clump State (YADE sets the member's vel from the clump's
    motion about the clump's centre: QDEM needs that centre), else None."""
    return O.bodies[b.clumpId].state if b.isClumpMember else None


def _clumpStates(states):
    """The list readSphereStates takes, or None when no sphere is a clump member."""
    return states if any(s is not None for s in states) else None


class SphereCoupling:
    """Per-engine state of the sphere coupling (created by QdemEngine)."""

    def __init__(self, world, mask=_PROXY_MASK_DEFAULT, margin=0.1):
        self.world = world
        self.mask = mask
        self.margin = margin
        self.proxies = []        # YADE ids of the proxies, one per piece
        self._bodies = []        # their Body objects (the same Python object while the body lives)
        self.proxyBox = []       # (lo, hi) each
        self.states = []         # YADE State objects of the listed spheres
        self.clumpStates = None  # their clumps' States (None for a free sphere); None: no clump member listed
        self.props = {}          # body id -> sphereProperties (cleared when bodies change)
        self._materials = {}     # id(material) -> (material, its values when read): checkChanged
        self.collider = None
        self._numAction = None
        self._dirty = True
        self._safeLo = self._safeHi = np.zeros((0, 3))
        self.refreshes = 0
        self.version = 0         # bumped whenever the sphere set changes (stable dt)
        self.seconds = 0.0       # wall time spent coupling (QdemEngine adds it up)

    # -- proxies -----------------------------------------------------------------
    def _findCollider(self, O):
        for e in O.engines:
            if type(e).__name__ == "InsertionSortCollider":
                return e
        raise RuntimeError("QdemEngine: coupling with YADE spheres needs an InsertionSortCollider in O.engines "
                           "(or set QdemEngine(spheres=False))")

    def _ensureCollider(self, O):
        if self.collider is None:
            self.collider = self._findCollider(O)
        funcs = list(self.collider.boundDispatcher.functors)
        if not any(type(f).__name__ == "Bo1_Tetra_Aabb" for f in funcs):
            self.collider.boundDispatcher.functors = funcs + [yade.Bo1_Tetra_Aabb()]

    def _grownBox(self, lo, hi):
        m = self.margin * max(float(np.max(hi - lo)), 1e-300)
        return lo - m, hi + m, m

    def _placeProxy(self, O, i, lo, hi):
        glo, ghi, _ = self._grownBox(lo, hi)
        centre = 0.5 * (glo + ghi)
        if i < len(self.proxies) and self.proxies[i] >= 0:
            b = O.bodies[self.proxies[i]]
        else:
            b = yade.Body()
            b.material = yade.FrictMat(label=_PROXY_LABEL, density=0.0)
            b.dynamic = False
            b.mask = self.mask
            b.shape = yade.Tetra()
            b.shape.wire = True
            bid = O.bodies.append(b)
            if i < len(self.proxies):
                self.proxies[i], self._bodies[i] = bid, b
            else:
                self.proxies.append(bid)
                self._bodies.append(b)
                self.proxyBox.append(None)
        b.shape.v = [yade.Vector3(*v) for v in _vertices(glo, ghi)]
        b.state.pos = yade.Vector3(*centre)
        self.proxyBox[i] = (glo, ghi)
        self.collider.doSort = True  # the collider sees the new bound at its next run
        self._dirty = True

    def adopt(self, proxies, boxes):
        """Take over the proxy bodies of a loaded scene (O.load keeps them in O.bodies)."""
        self.proxies = [int(b) for b in proxies]
        self._bodies = [None] * len(self.proxies)   # checked by _isProxy at the first step
        self.proxyBox = [(np.array(lo), np.array(hi)) for lo, hi in boxes]
        self._dirty = True  # lists read again; safe boxes recomputed at the first step

    def ownsBody(self, bid):
        return bid in self.proxies

    def _isProxy(self, O, i):
        """Is O.bodies[proxies[i]] still the proxy this coupling placed?"""
        bid = self.proxies[i]
        b = O.bodies[bid] if 0 <= bid < len(O.bodies) else None
        if b is None:
            return False
        if b is self._bodies[i]:
            return True
        # Another Python object for the same body (a loaded scene), or another body
        # at this id (O.bodies.clear() and new bodies appended).
        ok = looksLikeProxy(b)
        if ok:
            self._bodies[i] = b
        return ok

    def _replaceLostProxies(self, O):
        """Proxies erased by the script (O.bodies.erase in a clean-up loop,
        O.bodies.clear()) are placed again; until the collider has run, every
        sphere is listed against every piece, so no contact is missed."""
        lost = [i for i in range(len(self.proxies)) if not self._isProxy(O, i)]
        if not lost:
            return False
        warnings.warn("QdemEngine: the proxy bodies %s (which find YADE spheres near QDEM pieces) were erased or "
                      "replaced; placed them again. Exclude qe.proxyIds() from loops that erase bodies."
                      % [self.proxies[i] for i in lost], stacklevel=3)
        bounds = self.world.core.pieceBounds()
        for i in lost:
            self.proxies[i] = -1
            self._placeProxy(O, i, bounds[i, :3], bounds[i, 3:])
        self.props.clear()
        return True

    # -- per step ------------------------------------------------------------------
    def beforeStep(self, O):
        """Refreshes proxies and lists when needed, then reads the listed spheres' states."""
        core = self.world.core
        if self.collider is None:
            self._ensureCollider(O)
        if self._replaceLostProxies(O):
            self.listAll(O, withStates=True)
            self._numAction = None
            self._dirty = True
            if self.states:
                core.readSphereStates(self.states, self.clumpStates)
            return
        if not core.piecesInside(self._safeLo, self._safeHi):
            self._moveProxies(O, core.pieceBounds())
        # The collider ran (new lists) or interactions were erased with their
        # bodies (O.bodies.erase keeps the body count): list again.
        n = (self.collider.numAction, len(O.interactions))
        if self._dirty or n != self._numAction:
            self._refresh(O)
            self._numAction = n
            self._dirty = False
        if self.states:
            core.readSphereStates(self.states, self.clumpStates)

    def _moveProxies(self, O, bounds):
        """Places new proxies, and moves those whose piece came within half the
        margin of the proxy box: the collider only sees a moved proxy at its
        next run, and the piece may not outrun the other half meanwhile."""
        for i in range(len(bounds)):
            lo, hi = bounds[i, :3], bounds[i, 3:]
            if i >= len(self.proxies):
                self._placeProxy(O, i, lo, hi)
                continue
            plo, phi = self.proxyBox[i]
            m = self.margin * max(float(np.max(hi - lo)), 1e-300)
            if np.any(lo < plo + 0.5 * m) or np.any(hi > phi - 0.5 * m):
                self._placeProxy(O, i, lo, hi)
        safeLo, safeHi = [], []
        for (plo, phi), b in zip(self.proxyBox, bounds):
            m = self.margin * max(float(np.max(b[3:] - b[:3])), 1e-300)
            safeLo.append(plo + 0.5 * m)
            safeHi.append(phi - 0.5 * m)
        self._safeLo, self._safeHi = np.array(safeLo), np.array(safeHi)

    def _refresh(self, O):
        """Spheres listed by the collider against each proxy, to the core."""
        otherIds = _core.World.otherIds
        perPiece = [otherIds(O.interactions.withBodyAll(pid), pid) for pid in self.proxies]
        allIds = np.unique(np.concatenate(perPiece)) if perPiece else np.zeros(0, np.int32)
        props = self.props
        for bid in allIds.tolist():
            if bid not in props:
                b = O.bodies[bid]
                ok = b is not None and b.shape is not None and type(b.shape).__name__ == "Sphere"
                # walls, facets, boxes: QDEM sees them as obstacles, not here
                props[bid] = (sphereProperties(O, b), b.state, _clumpState(O, b)) if ok else False
                if ok:
                    self._noteMaterial(b)
        ids = [bid for bid in allIds.tolist() if props[bid] is not False]
        idArr = np.array(ids, dtype=np.int32)
        # CSR of the pieces each sphere may touch (pieces in proxy order).
        counts = np.zeros(len(ids) + 1, np.int32)
        pieceLists = []
        for piece, near in enumerate(perPiece):
            k = np.searchsorted(idArr, near)
            ok = (k < len(ids)) & (idArr[np.minimum(k, max(len(ids) - 1, 0))] == near) if len(ids) else near < 0
            pieceLists.append((k[ok], piece))
        owner = np.concatenate([k for k, _ in pieceLists]) if pieceLists else np.zeros(0, np.int64)
        piece = np.concatenate([np.full(len(k), p, np.int32) for k, p in pieceLists]) if pieceLists \
            else np.zeros(0, np.int32)
        order = np.argsort(owner, kind="stable")
        np.add.at(counts, owner + 1, 1)
        start = np.cumsum(counts).astype(np.int32)
        table = np.array([props[bid][0] for bid in ids], dtype=float).reshape(-1, 6)
        self.world.core.setSpheres(idArr, table[:, 0], table[:, 1], table[:, 2], table[:, 3], table[:, 4],
                                   table[:, 5], start, piece[order].astype(np.int32))
        self.states = [props[bid][1] for bid in ids]
        self.clumpStates = _clumpStates([props[bid][2] for bid in ids])
        self.refreshes += 1
        self.version += 1

    def listAll(self, O, withStates=False):
        """Lists every sphere of the scene against every piece (for a stable time
        step that holds whichever spheres come near, or, withStates, for the
        steps before the collider has seen new proxies); the next step re-lists."""
        self._ensureCollider(O)
        for bid in range(len(O.bodies)):
            if bid not in self.props:
                b = O.bodies[bid]
                ok = b is not None and b.shape is not None and type(b.shape).__name__ == "Sphere"
                self.props[bid] = (sphereProperties(O, b), b.state, _clumpState(O, b)) if ok else False
                if ok:
                    self._noteMaterial(b)
        ids = [bid for bid, p in self.props.items() if p is not False]
        props = np.array([self.props[bid][0] for bid in ids], dtype=float).reshape(-1, 6)
        n, np_ = len(ids), self.world.core.nPieces
        self.world.core.setSpheres(np.array(ids, dtype=np.int32), props[:, 0], props[:, 1], props[:, 2],
                                   props[:, 3], props[:, 4], props[:, 5],
                                   np.arange(0, n * np_ + 1, np_, dtype=np.int32),
                                   np.tile(np.arange(np_, dtype=np.int32), n))
        self.states = [self.props[bid][1] for bid in ids] if withStates else []
        self.clumpStates = _clumpStates([self.props[bid][2] for bid in ids]) if withStates else None
        self._dirty = True
        self.version += 1

    def checkChanged(self, O, full):
        """Applies changes the script made to listed spheres since they were
        read (their properties are cached per body): the values of their
        materials every step (a few objects: utils.setContactFriction, an
        edited frictionAngle), and with `full` each sphere's radius, material
        and mass (utils.growParticles, a new material; at the start of each
        O.run and every checkPeriod steps).  These were read once and kept:
        a grown sphere sat inside the piece, a sphere made frictionless
        stuck."""
        mats = self._materials
        changed = any(yadeglue.materialSignature(m) != sig for m, sig in mats.values())
        if not changed and full:
            for bid, p in self.props.items():
                if p is False:
                    continue
                b = O.bodies[bid] if bid < len(O.bodies) else None
                if b is None or b.shape is None or sphereProperties(O, b) != p[0]:
                    changed = True
                    break
        if changed:
            self.props.clear()
            self._materials = {}
            self._dirty = True

    def _noteMaterial(self, b):
        m = b.material
        self._materials.setdefault(id(m), (m, yadeglue.materialSignature(m)))

    def bodiesChanged(self):
        """Bodies were added or erased: forget cached properties and re-list."""
        self.props.clear()
        self._materials = {}
        self._dirty = True
        self.collider = None  # engines may have changed too: look again

    def afterStep(self, O):
        if self.states:
            self.world.core.applySphereForces(O.forces)
