"""QDEM under YADE's own MPI mode, ``yade.mpy`` (doc/parallel.md, "Under yade.mpy").

mpy gives each rank other YADE bodies: walls, boxes and facets stay on the
rank their ``Body.subdomain`` names (mpy's master, rank 0, by default), each
sphere on its subdomain's rank, and a rank's scene keeps only its own bodies
and copies of those touching them.  QDEM's split needs every rank to know the
obstacles and the spheres that may touch a piece, so beside mpy's messages
this layer does, every step, on every rank:

1. one allgather, on a communicator duplicated from mpy's (so it never meets
   mpy's ``ANY_SOURCE`` probes), of the obstacles and of the spheres near a
   piece that the rank owns (``Body.subdomain == rank``): states, and the
   sphere's contact properties;  every rank then gives QDEM the same
   obstacles and spheres, ordered by body id;
2. QDEM's step, split as under plain mpiexec: each sphere-piece pair is
   computed once, by the rank owning the pair (SpherePhase), and its force
   reaches every rank through the step's reduction;
3. each obstacle's reaction and each sphere's force and torque added to
   ``O.forces`` on the rank that owns the body only, where mpy integrates it.

QDEM's nodes are split over mpy's workers (ranks 1 .. P-1: the master holds
no share, as it holds no spheres), and `assignSubdomains` puts each sphere
(each clump, members with it) on the worker owning the piece surface nearest
to it, so that spheres live with the surface they touch.  Proxy bodies are
not used: bodies appended after mpy's split break its ids."""
import numpy as np
from yade import O, Vector3

from .. import _core
from ..mpi import ranks
from ..world import defaultWorld
from . import glue as yadeglue
from .spheres import sphereProperties

_ROW = 19  # id, radius, young, ks/kn, friction, restitution, mass, pos (3), vel (3), angVel (3), spin centre (3)


module = ranks.mpyModule  # yade.mpy when the script runs under it on more than one rank, else None


def attach(world):
    """Splits `world` over mpy's ranks, the master (rank 0) owning no node.
    Collective: every rank's QdemEngine calls it at its first step, once mpy
    has split the scene (O.splitted)."""
    mp = module()
    if world.core.mpiSize > 1:
        return
    ranks.requireMpi(mp.numThreads)
    world.core.setCommunicator(mp.comm, firstRank=1)


def _nearestOwner(points, surfPos, surfOwner, chunk=2048):
    """For each point, the owner of its nearest surface node (chunks of
    points against all surface nodes: O(points x nodes), done once)."""
    out = np.zeros(len(points), np.int32)
    s2 = np.einsum("ij,ij->i", surfPos, surfPos)
    for a in range(0, len(points), chunk):
        p = points[a:a + chunk]
        d = s2[None, :] - 2.0 * p @ surfPos.T  # |p - s|^2 - |p|^2: the same argmin
        out[a:a + chunk] = surfOwner[np.argmin(d, axis=1)]
    return out


def assignSubdomains(world=None):
    """Sets ``Body.subdomain`` of every YADE sphere and clump from QDEM's own
    split (the one its first step makes): the worker owning the piece surface
    node nearest to the sphere (to the clump's centre of mass, for the clump
    and all its members).  Call it before ``mp.mpirun``; a no-op serially or
    without yade.mpy.  Returns {rank: bodies}.  Walls, boxes and facets keep
    their subdomain (0: mpy's master)."""
    mp = module()
    if mp is None:
        return {}
    w = world or defaultWorld()
    core = w.core
    if core.nPieces == 0:
        raise RuntimeError("qdem.yade.mpy.assignSubdomains: the QDEM world has no piece yet: add the pieces first "
                           "(the spheres go to the ranks owning the surfaces near them)")
    owner = np.asarray(core.splitPreview(mp.numThreads, 1))
    surf = np.asarray(core.surfaceNodeIds)
    surfPos = np.array(core.pos)[surf]
    groups = []  # (centre, [body ids])
    for b in O.bodies:
        if b is None or b.isSubdomain:
            continue
        if b.isClump:
            groups.append((b.state.pos, [b.id] + [int(i) for i in b.shape.members.keys()]))
        elif not b.isClumpMember and type(b.shape).__name__ == "Sphere":
            groups.append((b.state.pos, [b.id]))
    if not groups:
        return {}
    ranks = _nearestOwner(np.array([[c[0], c[1], c[2]] for c, _ in groups]), surfPos, owner[surf])
    counts = {}
    for (_, ids), r in zip(groups, ranks.tolist()):
        for i in ids:
            O.bodies[i].subdomain = int(r)
        counts[int(r)] = counts.get(int(r), 0) + len(ids)
    return counts


class MpyCoupling:
    """Per-engine state of the coupling under yade.mpy (created by QdemEngine)."""

    def __init__(self, world, mp, margin):
        self.world = world
        self.mp = mp
        self.rank = int(mp.rank)
        self.margin = margin
        self.comm = None            # QDEM's own duplicate of mpy's communicator
        self._scanKey = None        # (bodies, collider runs) at the last scan
        self.obstacleIds = []       # the obstacles this rank owns (their ids, ascending)
        self.myDescr = []           # their descriptions (_describe)
        self._sentDescr = False
        self.descr = {}             # rank -> its obstacles' descriptions
        self.coreObstacleIds = []   # every rank's, ascending: QDEM's obstacle order
        self.sphereBodies = []      # (id, body) of the spheres this rank owns
        self.props = {}             # id -> sphereProperties
        self.sphereIds = np.zeros(0, np.int64)  # QDEM's sphere order (every rank's near spheres)
        self._pairs = None
        self.version = 0            # bumped when QDEM's sphere set changes (stable dt)
        self.seconds = 0.0

    # -- what this rank owns -----------------------------------------------------
    def _scan(self, O):
        obstacles, ids = yadeglue.scanObstacles(O)
        mine = [(o, i) for o, i in zip(obstacles, ids) if O.bodies[i].subdomain == self.rank]
        self.obstacleIds = [i for _, i in mine]
        self.myDescr = [_describe(O.bodies[i]) for _, i in mine]
        self._sentDescr = False
        self.sphereBodies = [(b.id, b) for b in O.bodies if b is not None and not b.isSubdomain
                             and b.subdomain == self.rank and type(b.shape).__name__ == "Sphere"]
        self.props = {bid: sphereProperties(O, b) for bid, b in self.sphereBodies}

    def _myRows(self, O, boxes):
        """This rank's obstacle states (k, 17) and its spheres near a piece (n, _ROW)."""
        obs = np.zeros((len(self.obstacleIds), 17))
        if self.obstacleIds:
            states = yadeglue.obstacleStates(O, self.obstacleIds, np.zeros((len(self.obstacleIds), 16)))
            if states is None:
                return None
            obs[:, 0], obs[:, 1:] = self.obstacleIds, states
        rows = []
        for bid, b in self.sphereBodies:
            s = b.state
            p = s.pos
            r = b.shape.radius
            x = np.array((p[0], p[1], p[2]))
            if len(boxes) and np.any(np.all((x - r <= boxes[:, 3:]) & (boxes[:, :3] <= x + r), axis=1)):
                v, a, sc = s.vel, s.angVel, p
                if b.isClumpMember:  # the clump's motion at the member (YADE sets member velocities
                    c = O.bodies[b.clumpId].state  # only in NewtonIntegrator: zero before its first step)
                    a, sc = c.angVel, c.pos
                    v = c.vel + a.cross(p - c.pos)
                rows.append((bid,) + self.props[bid] + (p[0], p[1], p[2], v[0], v[1], v[2], a[0], a[1], a[2],
                                                         sc[0], sc[1], sc[2]))
        return obs, np.array(rows, dtype=float).reshape(-1, _ROW)

    # -- per step ------------------------------------------------------------------
    def beforeStep(self, O):
        core = self.world.core
        if self.comm is None:
            self.comm = self.mp.comm.Dup()
        # Bodies change hands (mpy's reallocation, copies of other ranks'
        # bodies arriving or leaving) only when mpy runs the collider: scan
        # what this rank owns again then, and when the body count changes.
        key = (len(O.bodies), _colliderRuns(O))
        if key != self._scanKey:
            self._scan(O)
            self._scanKey = key
        b = np.array(core.pieceBounds()) if core.nPieces else np.zeros((0, 6))  # (collective under MPI)
        m = self.margin * np.max(b[:, 3:] - b[:, :3], axis=1, initial=0.0)[:, None] if len(b) else 0.0
        boxes = np.hstack([b[:, :3] - m, b[:, 3:] + m]) if len(b) else b
        mine = self._myRows(O, boxes)
        if mine is None:  # a body was erased: scan again
            self._scan(O)
            mine = self._myRows(O, boxes)
        descr = None if self._sentDescr else self.myDescr
        self._sentDescr = True
        every = self.comm.allgather((descr, mine[0], mine[1]))
        changed = False
        for r, (d, _, _) in enumerate(every):
            if d is not None:
                self.descr[r] = d
                changed = True
        obs = np.concatenate([e[1] for e in every])
        order = np.argsort(obs[:, 0], kind="stable")
        obs = obs[order]
        if changed:
            byId = {d[0]: d for ds in self.descr.values() for d in ds}
            self.coreObstacleIds = [int(i) for i in obs[:, 0]]
            core.setObstacles([_obstacle(_core, byId[i]) for i in self.coreObstacleIds])
        if len(obs):
            core.setObstacleStates(np.ascontiguousarray(obs[:, 1:]))
        sph = np.concatenate([e[2] for e in every])
        sph = sph[np.argsort(sph[:, 0], kind="stable")]
        self._setSpheres(core, sph, boxes)

    def _setSpheres(self, core, sph, boxes):
        x, r = sph[:, 7:10], sph[:, 1:2]
        if len(boxes):
            near = np.all((x[:, None, :] - r[:, :, None] <= boxes[None, :, 3:])
                          & (boxes[None, :, :3] <= x[:, None, :] + r[:, :, None]), axis=2)
        else:
            near = np.zeros((len(sph), 0), bool)
        start = np.concatenate([[0], np.cumsum(near.sum(axis=1))]).astype(np.int32)
        pieces = np.nonzero(near)[1].astype(np.int32)
        key = (sph[:, :7].tobytes(), start.tobytes(), pieces.tobytes())
        if key != self._pairs:
            core.setSpheres(sph[:, 0].astype(np.int32), sph[:, 1], sph[:, 2], sph[:, 3], sph[:, 4], sph[:, 5],
                            sph[:, 6], start, pieces)
            self._pairs = key
            self.sphereIds = sph[:, 0].astype(np.int64)
            self.version += 1
        if len(sph):
            core.setSphereStates(np.ascontiguousarray(x), np.ascontiguousarray(sph[:, 10:13]),
                                 np.ascontiguousarray(sph[:, 13:16]), np.ascontiguousarray(sph[:, 16:19]))

    def afterStep(self, O):
        """Reactions and sphere forces to the bodies this rank owns."""
        core = self.world.core
        if self.obstacleIds:
            mine = set(self.obstacleIds)
            rows = [(i, r) for i, r in zip(self.coreObstacleIds, core.obstacleReactions()) if i in mine]
            yadeglue.applyReactions(O, [i for i, _ in rows], [r for _, r in rows])
        if len(self.sphereIds) and self.sphereBodies:
            mine = {bid for bid, _ in self.sphereBodies}
            ft = core.sphereForceTorque()
            for bid, f in zip(self.sphereIds.tolist(), ft):
                if bid in mine and np.any(f):
                    O.forces.addF(bid, Vector3(f[0], f[1], f[2]))
                    O.forces.addT(bid, Vector3(f[3], f[4], f[5]))


def _colliderRuns(O):
    for e in O.engines:
        if type(e).__name__ == "InsertionSortCollider":
            return e.numAction
    return 0


def _describe(b):
    """A picklable description of a Wall, Box or Facet body (its shape, not its state)."""
    kind = yadeglue.KIND[type(b.shape).__name__]
    young = float(getattr(b.material, "young", 0.0) or 0.0)
    if kind == 0:
        return (b.id, kind, young, int(b.shape.axis), int(b.shape.sense))
    if kind == 1:
        e = b.shape.extents
        return (b.id, kind, young, (e[0], e[1], e[2]))
    return (b.id, kind, young, tuple((p[0], p[1], p[2]) for p in b.shape.vertices))


def _obstacle(_core, d):
    o = _core.Obstacle()
    o.bodyId, o.kind, o.young = d[0], d[1], d[2]
    if d[1] == 0:
        o.axis, o.sense = d[3], d[4]
    elif d[1] == 1:
        o.halfExtents = np.array(d[3])
    else:
        o.setVertices(*[np.array(v) for v in d[3]])
    return o


__all__ = ["assignSubdomains"]
