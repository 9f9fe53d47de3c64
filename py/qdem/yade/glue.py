"""Reading YADE's scene: rigid obstacles (Wall, Box, Facet), gravity, O.forces,
and which bodies are QDEM's own proxies.  The lowest module of the YADE host
(qdem.yade): the model below it (qdem.world, qdem.piece, ...) runs without YADE."""
import math
import warnings

import numpy as np
from yade import Vector3

from .. import _core

KIND = {"Wall": 0, "Box": 1, "Facet": 2}
PROXY_LABEL = "qdemProxy"  # material label of the proxy bodies (spheres.py)


def looksLikeProxy(b):
    """Is YADE body b one of QDEM's proxy bodies (a non-dynamic Tetra of the
    proxy material)?"""
    mat = b.material
    return (mat is not None and mat.label == PROXY_LABEL and type(b.shape).__name__ == "Tetra"
            and not b.dynamic)


def findGravity(O):
    """Gravity of the first NewtonIntegrator in O.engines (zero when none)."""
    for e in O.engines:
        if type(e).__name__ == "NewtonIntegrator":
            g = e.gravity
            return (g[0], g[1], g[2])
    return (0.0, 0.0, 0.0)


def _friction(b):
    """Coulomb coefficient of body b's material: tan(frictionAngle), as YADE's
    FrictPhys; -1 (none: the piece's frictionWall alone) for a material without one."""
    angle = getattr(b.material, "frictionAngle", None)
    if angle is None:
        return -1.0
    angle = float(angle)
    if not (0.0 <= angle < 0.5 * math.pi):
        raise ValueError("YADE body %d (%s): its material's frictionAngle = %r rad is not in [0, pi/2): "
                         "give it the angle in radians, e.g. math.atan(0.5) for a coefficient of 0.5"
                         % (b.id, type(b.shape).__name__, angle))
    return math.tan(angle)


def _mobility(O, b):
    """(1/mass, 1/smallest moment of inertia, arm offset) of what YADE moves when body
    b is pushed: zeros for a fixed body; a term only for free translations or
    rotations (blockedDOFs); inf for a free one of zero mass or inertia; a clump
    member's clump, with the distance from the member to the clump's centre."""
    mover = O.bodies[b.clumpId] if b.isClumpMember else b
    if mover is None or not mover.dynamic:
        return 0.0, 0.0, 0.0
    s = mover.state
    blocked = s.blockedDOFs
    invMass = invInertia = 0.0
    if any(c not in blocked for c in "xyz"):
        invMass = 1.0 / s.mass if s.mass > 0 else math.inf
    if any(c not in blocked for c in "XYZ"):
        inertia = min(s.inertia)
        invInertia = 1.0 / inertia if inertia > 0 else math.inf
    arm = float((b.state.pos - s.pos).norm()) if mover is not b else 0.0
    return invMass, invInertia, arm


def scanObstacles(O, bodies=None):
    """Core Obstacle objects for every Wall, Box and Facet body (of ``bodies``,
    default all of O.bodies), and their ids."""
    obstacles, ids = [], []
    for b in (O.bodies if bodies is None else bodies):
        if b is None or b.shape is None:
            continue
        kind = KIND.get(type(b.shape).__name__)
        if kind is None:
            continue
        o = _core.Obstacle()
        o.kind = kind
        o.bodyId = b.id
        young = getattr(b.material, "young", None)
        o.young = float(young) if young else 0.0
        o.friction = _friction(b)
        o.invMass, o.invInertia, o.armOffset = _mobility(O, b)
        if kind == 0:
            o.axis, o.sense = int(b.shape.axis), int(b.shape.sense)
        elif kind == 1:
            e = b.shape.extents
            o.halfExtents = np.array([e[0], e[1], e[2]])
        else:  # facet vertices are stored relative to the body, in its frame
            v = b.shape.vertices
            o.setVertices(*[np.array([p[0], p[1], p[2]]) for p in v])
        obstacles.append(o)
        ids.append(b.id)
    return obstacles, ids


# Shapes QDEM pieces collide with: the obstacles (KIND), spheres (also clump
# members) and the clumps holding them.
_FELT = frozenset(KIND) | {"Sphere", "Clump"}


def unfeltBodies(O):
    """(id, shape name) of every body QDEM pieces would pass through: a shape
    that is not a Wall, Box, Facet or Sphere (Polyhedra, GridNode,
    GridConnection, PFacet, Tetra, ...), less QDEM's own proxy bodies and
    yade.mpy's subdomains.  (Spheres with QdemEngine(spheres=False) are not
    listed: the script asked for that.)"""
    out = []
    for b in O.bodies:
        if b is None or b.shape is None:
            continue
        name = type(b.shape).__name__
        if name in _FELT:
            continue
        if getattr(b, "isSubdomain", False):
            continue
        if name == "Tetra" and looksLikeProxy(b):
            continue
        out.append((b.id, name))
    return out


def hasSpheres(O):
    """Is there any Sphere body (standalone or clump member) in the scene?"""
    return any(b is not None and type(b.shape).__name__ == "Sphere" for b in O.bodies)


_MATERIAL_KEYS = ("young", "poisson", "frictionAngle", "en")
_materialKeys = {}  # material class -> which of _MATERIAL_KEYS it has (getattr with a default raises inside)


def materialSignature(m):
    """The material values the contacts read (young, poisson, frictionAngle,
    en; None for those the class lacks): a change made by the script mid-run
    (utils.setContactFriction, a new material) must reach QDEM's copy; it was
    read once and kept."""
    keys = _materialKeys.get(type(m))
    if keys is None:
        keys = _materialKeys[type(m)] = tuple(k if hasattr(m, k) else None for k in _MATERIAL_KEYS)
    return tuple(getattr(m, k) if k is not None else None for k in keys)


def bodySignature(b, materials=None, state=None):
    """What the obstacle's core copy was built from: its shape, whether and
    how YADE moves it (dynamic, blockedDOFs, mass) and its material's values
    (None: not an obstacle).  materials: a dict kept over one pass through
    the obstacles, so that a material shared by many bodies (a facet
    container's) is read once (it holds the material object, so its id is
    not reused meanwhile); state: b.state when the caller has it."""
    shape = b.shape
    kind = KIND.get(type(shape).__name__) if shape is not None else None
    if kind is None:
        return None
    s, m = state or b.state, b.material
    if materials is None:
        ms = materialSignature(m)
    else:
        known = materials.get(id(m))
        if known is None:
            known = materials[id(m)] = (m, materialSignature(m))
        ms = known[1]
    moved = (b.dynamic, s.blockedDOFs, s.mass, ms)
    if kind == 0:
        return (0, shape.axis, shape.sense, moved)
    if kind == 1:  # (extents is a live reference to the shape's: its numbers are kept)
        return (1, shape.extents.__getinitargs__(), moved)
    return (2, moved, shape.vertices)  # (a list of Vector3 copies, compared by value)


def obstacleStates(O, ids, out, signatures=None, reshaped=None, seen=None, written=None):
    """Fill out (k,16) with pos, quaternion (w x y z), vel, angVel and spin centre
    of the bodies (the clump's centre for a clump member, whose vel YADE sets
    from the clump's motion about it; else pos: Obstacle::velocityAt);
    None when one of them was erased (scan again).  With ``signatures`` (one
    bodySignature per body), the index of each body whose shape changed since
    (a Box's extents, a Facet's vertices, a body of another kind after
    O.bodies.clear()) or that was made dynamic or fixed is appended to ``reshaped``.

    Every step reads every obstacle (a facet container has hundreds), so this
    is written for few Python operations per body: with ``seen`` (a list kept
    by the caller for this ``out``, one entry per body) a row is written only
    when the body's pos, ori, vel or angVel differ from the last call's; the
    index of each row written is appended to ``written``."""
    bodies = O.bodies
    n = len(bodies)
    materials = {} if signatures is not None else None
    for i, bid in enumerate(ids):
        b = bodies[bid] if bid < n else None
        if b is None:  # erased since the last scan
            return None
        s = b.state
        if signatures is not None and bodySignature(b, materials, s) != signatures[i]:
            reshaped.append(i)
        # (minieigen's __getinitargs__: the numbers as a tuple of floats, a copy
        # - vel and angVel are live references into the state - in one call;
        # a quaternion's as w x y z; the core normalises it)
        if b.isClumpMember:  # the clump's motion at the member (YADE sets a member's own vel only in
            cs = bodies[b.clumpId].state  # NewtonIntegrator: zero before its first step)
            p, c, w = s.pos, cs.pos, cs.angVel
            row = (p.__getinitargs__() + s.ori.__getinitargs__() + (cs.vel + w.cross(p - c)).__getinitargs__()
                   + w.__getinitargs__() + c.__getinitargs__())
        else:
            p = s.pos.__getinitargs__()
            row = p + s.ori.__getinitargs__() + s.vel.__getinitargs__() + s.angVel.__getinitargs__() + p
        if seen is not None:
            if row == seen[i]:
                continue
            seen[i] = row
        out[i] = row
        if written is not None:
            written.append(i)
    return out


def applyReactions(O, ids, reactions):
    """Add each obstacle's reaction force and torque to O.forces."""
    rows = np.asarray(reactions, dtype=float).reshape(-1, 6).tolist()  # (Python floats: a NumPy row costs 10x)
    for bid, r in zip(ids, rows):
        if r[0] or r[1] or r[2] or r[3] or r[4] or r[5]:
            O.forces.addF(bid, Vector3(r[0], r[1], r[2]))
            O.forces.addT(bid, Vector3(r[3], r[4], r[5]))


class PosDrivenWatch:
    """Warns, once per body, when a script moves an obstacle by writing its
    state.pos with a velocity that does not match the move (typically 0): QDEM
    takes an obstacle's surface velocity from state.vel and angVel, so its
    contact dashpots and friction see the body still and qdemBoundaryWork
    books none of its work (a wall pushed down by pos += each step did
    0.094 J of work on a block that the ledger never saw).  Judged over
    consecutive steps: a body placed once between runs is not a driven one.
    A move matches when it is the step's chord of the body's vel at either
    end (YADE's kinematic engines set vel to it, before or after QdemEngine)."""

    STEPS = 3  # consecutive mismatched moves before the warning

    def __init__(self):
        self.prev = None      # (ids, O.iter, pos, vel, dt) of the last step
        self.still = False    # at the last step nothing moved and every vel was zero
        self.count = {}       # body id -> consecutive mismatched moves
        self.warned = set()

    def watch(self, O, ids, states, changed=True):
        """ids: the engine's list of obstacle ids (the same list object until
        it scans O.bodies again); changed: whether any row of states differs
        from the last call's (False: only the step is new)."""
        prev = self.prev
        if not changed and self.still and prev is not None and prev[0] is ids and prev[1] == O.iter - 1:
            # Nothing moved and nothing has a velocity, as at the last step:
            # nothing to judge (walls and facet containers, every step).
            self.prev = (ids, O.iter, prev[2], prev[3], O.dt)
            return
        pos, vel = states[:, 0:3].copy(), states[:, 7:10].copy()
        self.prev = (ids, O.iter, pos, vel, O.dt)
        self.still = False
        if prev is None or prev[0] is not ids or prev[1] != O.iter - 1:
            self.count.clear()
            return
        moved = pos - prev[2]
        if not (moved.any() or vel.any() or prev[3].any()):  # all still: nothing to judge
            self.still = True
            self.count.clear()
            return
        dist = np.linalg.norm(moved, axis=1)
        off = np.minimum(np.linalg.norm(moved - vel * prev[4], axis=1),
                         np.linalg.norm(moved - prev[3] * prev[4], axis=1))
        for k in np.nonzero(off > 0.1 * dist + 1e-12)[0]:
            bid = ids[k]
            self.count[bid] = self.count.get(bid, 0) + 1
            if self.count[bid] >= self.STEPS and bid not in self.warned:
                self.warned.add(bid)
                v = vel[k]
                warnings.warn("qdem: YADE body %d (%s) moved %.3g m in the last step while its state.vel is "
                              "(%.3g, %.3g, %.3g): it is driven by writing state.pos. QDEM takes an obstacle's "
                              "surface velocity from state.vel and angVel, so its contact dashpots and friction "
                              "see it moving at that velocity and qdemBoundaryWork books none of the work the "
                              "move does. Drive it by velocity (a TranslationEngine, or state.vel with "
                              "blockedDOFs) instead." % (bid, type(O.bodies[bid].shape).__name__, dist[k],
                                                         v[0], v[1], v[2]), RuntimeWarning, stacklevel=4)
        for k in np.nonzero(off <= 0.1 * dist + 1e-12)[0]:
            self.count.pop(ids[k], None)
