"""Random scenes for the fuzzer (test_fuzz.py) and their replay in the
regression tests (test_fuzz_regressions.py).

A scene is a plain dict (a *spec*: printable, and pasted as is into a
regression test); ``sceneSpecs()`` is the Hypothesis strategy drawing them and
``runScene(spec)`` builds the YADE scene, runs it with the invariants checked
after every step and returns an Outcome.  ``check(outcome)`` raises
AssertionError naming the first broken invariant.

Three kinds of scene, each made to collide within its run:

* ``pair``   two pieces thrown at each other, no gravity, nothing else: the
             total momentum is exact (to rounding) and neither piece passes
             through the other;
* ``drop``   one piece thrown (with or without gravity) at a YADE wall (any
             axis and side), a floor of two facets or a box;
* ``spheres`` a YADE sphere or a clump of spheres thrown at a piece, no
             gravity: momentum of spheres plus piece exact, no sphere ends
             inside the piece.

O.dt is ``dtFraction`` of QdemEngine.stableTimeStep(), with YADE spheres of
the smaller of that and YADE's utils.PWaveTimeStep() (doc/spheres.md §5).

Invariants checked every step: positions and velocities finite; the energy
ledger (QDEM's total plus the YADE bodies' kinetic energy, both at the step's
integer time level: _yadeKinetic) never above its
value after the first step by more than its first-order drift
``ENERGY_GAIN`` x dtFraction of the energy in flight (measured, see there);
momentum exact where nothing external acts; no piece centroid or sphere
centre deeper inside a piece than the contact's reach, no piece centroid
behind the obstacle it was thrown at (checked every ``PASS_CHECK`` steps and
at the end).  A gain or a pass that the engine names within its
``checkPeriod`` is a named stop; a gain above ``EXPLOSION`` fails anyway.
At the end: with Saint-Venant-Kirchhoff no element left inverted; ``O.dt``
at or below the stable step, drawn before and read again after the run.  A
*named stop* (qdem.StabilityError, qdem.SetupError or ValueError whose
message says what is wrong) is a correct outcome, except a StabilityError
for a non-finite state: the step is drawn below the stable one, so a NaN is a blow-up."""
import functools
import math
import os
import subprocess
import tempfile

import numpy as np

import qdem

# Ledger gain allowed, as a fraction of the energy in flight (the largest
# kinetic + elastic + contact-spring energy seen, plus the largest |gravity
# work|), per unit dtFraction: the contact dashpots' booked loss drifts to
# first order in dt (doc/hard_cases.md, "Known limits").  Measured: 0.069 f
# (two cubes at restitution 0.2, 5.5 % at f = 0.8), 0.052 f (two 3x3x3 cubes
# at restitution 0.5: 4.1 %, 2.0 %, 0.98 %, 0.48 % at f = 0.8, 0.4, 0.2,
# 0.1), below 0.02 f in the fuzzer's own well-behaved scenes (pieces, walls,
# facets, boxes; spheres 0.016 f).  Allowed: twice the largest.
ENERGY_GAIN = 0.15
EXPLOSION = 0.5         # a gain this large fails even if a named stop follows: a blow-up
MOMENTUM_REL = 1e-9      # |dp| / sum m|v| where nothing external acts
PASS_CHECK = 10          # steps between the (costlier) pass-through checks

NAMED_STOPS = ("StabilityError", "SetupError", "ValueError")


# ----------------------------------------------------------------- meshes ----

def _cacheDir():
    d = os.path.join(tempfile.gettempdir(), "qdem-fuzz-meshes-%d" % os.getuid())
    os.makedirs(d, exist_ok=True)
    return d


@functools.lru_cache(maxsize=None)
def _unitBall(cellsPerRadius, seed):
    m = qdem.ballMesh(1.0, 1.0 / cellsPerRadius, seed=seed)
    return np.array(m.nodes), np.array(m.tets)


def _prismSurface(sides, height):
    """A closed convex prism of `sides` sides, circumradius 1, as (verts, tris)."""
    a = 2 * np.pi * np.arange(sides) / sides
    ring = np.c_[np.cos(a), np.sin(a)]
    v = np.r_[np.c_[ring, np.full(sides, -height / 2)], np.c_[ring, np.full(sides, height / 2)],
              [[0, 0, -height / 2], [0, 0, height / 2]]]
    b, t = 2 * sides, 2 * sides + 1
    tris = []
    for i in range(sides):
        j = (i + 1) % sides
        tris += [(b, j, i), (t, sides + i, sides + j), (i, j, sides + j), (i, sides + j, sides + i)]
    return v, np.array(tris, dtype=np.int32)


@functools.lru_cache(maxsize=None)
def _unitCgalShape(kind, cellSize, seed):
    if kind == "prism":
        surf = _prismSurface(6, 1.2)
    elif kind == "octahedron":
        v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
        tris = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
        surf = (v, np.array(tris, dtype=np.int32))
    else:  # ellipsoid
        from qdem.shapes import icosphere
        v, t = icosphere(1.0, 2)
        surf = (v * [1.0, 0.6, 0.4], t)
    m = qdem.meshSurface(surf, cellSize, seed=seed)
    return np.array(m.nodes), np.array(m.tets)


def _writeOff(path, verts, tris):
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(verts), len(tris)))
        for p in verts:
            f.write("%.17g %.17g %.17g\n" % tuple(p))
        for t in tris:
            f.write("3 %d %d %d\n" % tuple(t))


@functools.lru_cache(maxsize=None)
def _unitTetgen(kind, maxVolume):
    """TetGen without its quality bound (-q): the Delaunay tetrahedra of the
    surface points, slivers (four nearly coplanar points) included."""
    from qdem.shapes import icosphere
    if kind == "ball":
        verts, tris = icosphere(1.0, 2)
    else:
        verts, tris = _prismSurface(8, 1.5)
    d = tempfile.mkdtemp(dir=_cacheDir())
    off = os.path.join(d, "s.off")
    _writeOff(off, verts, tris)
    flags = "-pQ" + ("a%g" % maxVolume if maxVolume else "")
    subprocess.run(["tetgen", flags, off], check=True, capture_output=True, timeout=60)
    m = qdem.loadMesh(os.path.join(d, "s.1.node"), fixOrientation=True)
    return np.array(m.nodes), np.array(m.tets)


def makeMesh(spec):
    """(nodes, tets) of a mesh spec; sizes in metres."""
    kind = spec["kind"]
    if kind == "box":
        m = qdem.boxMesh(tuple(spec["size"]), tuple(spec["cells"]), spec["tetsPerCell"])
        return np.array(m.nodes), np.array(m.tets)
    if kind == "ball":
        nodes, tets = _unitBall(spec["cellsPerRadius"], spec.get("seed", 0))
    elif kind == "cgal":
        nodes, tets = _unitCgalShape(spec["shape"], spec["cellSize"], spec.get("seed", 0))
    elif kind == "tetgen":
        nodes, tets = _unitTetgen(spec["shape"], spec["maxVolume"])
    else:
        raise ValueError("unknown mesh kind %r" % kind)
    return nodes * spec["size"], tets


def meshSize(nodes):
    """Smallest extent of the mesh's bounding box."""
    return float((nodes.max(axis=0) - nodes.min(axis=0)).min())


def edgeLength(nodes, tets):
    e = nodes[tets[:, [0, 0, 0, 1, 1, 2]]] - nodes[tets[:, [1, 2, 3, 2, 3, 3]]]
    return float(np.median(np.linalg.norm(e, axis=2)))


# ---------------------------------------------------------------- material ---

def makeMaterial(spec, nodes, tets):
    """QdemMat from a material spec: viscosity from a first-mode damping ratio
    (xi = eta omega / (2 mu), omega ~ pi c_s / L), radius a fraction of the
    median edge."""
    E, nu, rho = spec["young"], spec["poisson"], spec["density"]
    mu = E / (2 * (1 + nu))
    L = max(meshSize(nodes), 1e-9)
    omega = math.pi * math.sqrt(mu / rho) / L
    eta = spec["xi"] * 2 * mu / omega
    return qdem.QdemMat(young=E, poisson=nu, density=rho, viscosity=eta, radius=spec["radiusFraction"] *
                        edgeLength(nodes, tets), restitution=spec["restitution"], frictionPiece=spec["friction"],
                        frictionWall=spec["friction"], law=spec["law"])


# ------------------------------------------------------------------ checks ---

def _pointsInside(points, nodes, tets):
    """Boolean per point: inside one of the tetrahedra (barycentric test)."""
    if len(points) == 0:
        return np.zeros(0, bool)
    a = nodes[tets[:, 0]]
    T = np.stack([nodes[tets[:, k]] - a for k in (1, 2, 3)], axis=2)       # (t,3,3)
    det = np.linalg.det(T)
    ok = np.abs(det) > 0
    Tinv = np.zeros_like(T)
    Tinv[ok] = np.linalg.inv(T[ok])
    d = points[:, None, :] - a[None, :, :]                                     # (p,t,3)
    lam = np.einsum("tij,ptj->pti", Tinv, d)
    inside = (lam >= 0).all(axis=2) & (lam.sum(axis=2) <= 1) & ok[None, :]
    return inside.any(axis=1)


def _yadeKinetic(O, ids, before):
    """Kinetic energy (translation + rotation) of the YADE bodies `ids`
    (standalone spheres and clumps) at the step's integer time level, where
    QDEM books its nodes' kinetic energy and every contact spring: the
    velocities halfway between those before the step (`before`: id ->
    (vel, angVel), updated to the new ones) and after it.  YADE's leapfrog
    holds v(t + dt/2) after its step (and books O.energy['kinetic'] with
    v(t - dt/2)); summed with QDEM's terms at t, the half-step mismatch,
    (dt/2) F.v, read as a first-order drift of up to 1.2 f for a light
    sphere on a soft cube (test_fuzz_regressions.py)."""
    from yade import Vector3
    e = 0.0
    for i in ids:
        s = O.bodies[i].state
        v1, w1 = np.array(s.vel), np.array(s.angVel)
        v0, w0 = before.get(i, (v1, w1))
        before[i] = (v1, w1)
        v = 0.5 * (v0 + v1)
        e += 0.5 * s.mass * v @ v
        w = s.ori.conjugate() * Vector3(*(0.5 * (w0 + w1)))
        e += 0.5 * sum(s.inertia[k] * w[k] ** 2 for k in range(3))
    return e


def _yadeMomentum(O, ids):
    return sum((O.bodies[i].state.mass * np.array(O.bodies[i].state.vel) for i in ids), np.zeros(3))


class Outcome:
    """What a run gave: the first broken invariant (``failure``), or none;
    the named stop it ended with (``stop``), the worst figures seen."""

    def __init__(self, spec):
        self.spec = spec
        self.failure = None
        self.stop = None
        self.steps = 0
        self.dt = None
        self.stableDt = None
        self.energyGain = 0.0       # largest (ledger - start) / scale
        self.energyScale = None
        self.momentumError = 0.0    # largest |dp| / sum m|v|
        self.contacted = False
        self.minRadius = 0.0        # smallest contact radius of the scene
        self.warnings = []

    def fail(self, msg):
        if self.failure is None:
            self.failure = "step %d: %s" % (self.steps, msg)

    def __repr__(self):
        return ("Outcome(failure=%r, stop=%r, steps=%d, dt=%.3g, energyGain=%.3g, momentumError=%.3g, "
                "contacted=%s)" % (self.failure, self.stop, self.steps, self.dt or 0, self.energyGain,
                                   self.momentumError, self.contacted))


def check(outcome):
    assert outcome.failure is None, "%s\nspec = %r" % (outcome.failure, outcome.spec)


# Defects found by the fuzzer whose fixes belong elsewhere (their shrunk scenes
# are strict xfails in test_fuzz_regressions.py).  A failure matching one is
# reported, not failed, unless QDEM_FUZZ_STRICT=1: remove the entry with the fix.
def _supersonic(spec, out):
    """A NaN where a node moves more than its contact radius per step (against
    a one-sided wall fixed: a piece crushed through itself is named)."""
    f = out.failure or ""
    ob = spec.get("obstacle") or {}
    oneSidedWall = ob.get("kind") == "wall" and ob.get("sense", 0) != 0
    return ("non-finite" in f or "not finite" in f or "blow-up" in f or "exploded" in f) and \
        spec["speed"] * (out.dt or 0) > out.minRadius and not oneSidedWall


def _softContactStep(spec, out):
    """A blow-up (not a moderate gain) at a step below stableTimeStep(), pieces against pieces or walls."""
    f = out.failure or ""
    return spec["kind"] in ("pair", "drop") and ("exploded" in f or "blow-up" in f or "non-finite" in f)


def _sinkThrough(spec, out):
    """A piece sinking through the obstacle its contacts cannot hold, unnamed."""
    return spec["kind"] == "drop" and "passed through" in (out.failure or "")


KNOWN_DEFECTS = {
    "soft piece sinks through a wall, box or facets unnamed": _sinkThrough,
    "supersonic impact ends in NaN, not a named stop": _supersonic,
    "contact stable step too large (blow-up below stableTimeStep)": _softContactStep,
}


def knownDefect(outcome):
    """The name of the known defect the failure matches, or None."""
    if outcome.failure is None:
        return None
    for name, match in KNOWN_DEFECTS.items():
        if match(outcome.spec, outcome):
            return name
    return None


# ---------------------------------------------------------------- the run ----

def _engines(spec, withSpheres):
    from yade import (Bo1_Box_Aabb, Bo1_Facet_Aabb, Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter,
                      Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                      Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)
    g = (0, 0, -9.81) if spec.get("gravity") else (0, 0, 0)
    qe = qdem.QdemEngine(threads=spec["threads"])
    pre = []
    if withSpheres:
        pre = [InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb(), Bo1_Facet_Aabb(), Bo1_Box_Aabb()]),
               InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                               [Law2_ScGeom_FrictPhys_CundallStrack()])]
    return [ForceResetter()] + pre + [qe, NewtonIntegrator(gravity=g, damping=0.0)], qe


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _perp(d, angle):
    """A unit vector perpendicular to d, turned by angle about d."""
    a = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    u = _unit(np.cross(d, a))
    w = np.cross(d, u)
    return math.cos(angle) * u + math.sin(angle) * w


def _addObstacle(O, ob, size):
    """A YADE obstacle whose contact plane passes through the origin with
    outward normal n (returned), pieces coming from the +n side."""
    from yade import FrictMat, Vector3, utils
    fm = O.materials.append(FrictMat(young=1e9, poisson=0.3, frictionAngle=ob.get("frictionAngle", 0.5),
                                     density=1000))
    kind = ob["kind"]
    if kind == "wall":
        axis, sense = ob["axis"], ob["sense"]
        O.bodies.append(utils.wall(0.0, axis=axis, sense=sense, material=fm))
        n = np.zeros(3)
        n[axis] = sense if sense else 1
        return n
    big = 50 * size
    if kind == "facets":
        pts = [(-big, -big, 0), (big, -big, 0), (big, big, 0), (-big, big, 0)]
        for tri in [(0, 1, 2), (0, 2, 3)]:
            O.bodies.append(utils.facet([Vector3(*pts[k]) for k in tri], fixed=True, material=fm))
    else:  # box: its top face at z = 0
        O.bodies.append(utils.box((0, 0, -size), (big, big, size), fixed=True, material=fm))
    return np.array([0, 0, 1.0])


def runScene(spec):
    """Build and run a scene spec inside YADE; returns an Outcome."""
    from yade import FrictMat, O, PyRunner, Vector3, utils
    import warnings
    out = Outcome(spec)
    O.reset()
    qdem.reset()
    kind = spec["kind"]
    try:  # a mesh the mesher refuses, naming why and what to change, is a named stop too
        meshes = [makeMesh(p["mesh"]) for p in spec["pieces"]]
    except Exception as e:  # noqa: BLE001 - classified in _stopped
        return _stopped(out, e)
    mats = [makeMaterial(p["material"], *m) for p, m in zip(spec["pieces"], meshes)]
    pieces = []
    for p, (nodes, tets), mat in zip(spec["pieces"], meshes, mats):
        nodes = nodes - nodes.mean(axis=0)
        pieces.append(qdem.addPiece((nodes, tets), mat, ori=(tuple(p["oriAxis"]), p["oriAngle"])))
    sizes = [meshSize(m[0]) for m in meshes]
    out.minRadius = min(m.radius for m in mats)
    normal = None
    sphereIds, dynIds = [], []
    if kind == "drop":
        normal = _addObstacle(O, spec["obstacle"], sizes[0])
    elif kind == "spheres":
        sp = spec["spheres"]
        fm = O.materials.append(FrictMat(young=sp["young"], poisson=0.3, frictionAngle=sp["frictionAngle"],
                                         density=sp["density"]))
        R = sp["radiusFraction"] * sizes[0]
        if sp["clump"]:
            offs = [(-0.6 * R, 0, 0), (0.6 * R, 0, 0), (0, 0.6 * R, 0.3 * R)]
            cid, members = O.bodies.appendClumped([utils.sphere(o, R * 0.7, material=fm) for o in offs])
            dynIds, sphereIds = [cid], list(members)
        else:
            sid = O.bodies.append(utils.sphere((0, 0, 0), R, material=fm))
            dynIds = sphereIds = [sid]
    engines, qe = _engines(spec, kind == "spheres")
    O.engines = engines
    try:
        stable = qe.stableTimeStep()
    except Exception as e:  # noqa: BLE001 - classified below
        return _stopped(out, e)
    if kind == "spheres":  # with YADE spheres, the smaller of QDEM's step and YADE's own (doc/spheres.md §5)
        stable = min(stable, utils.PWaveTimeStep())
    out.stableDt = stable
    dt = spec["dtFraction"] * stable
    out.dt = dt
    steps = spec["steps"]
    # Placement: the gap closes within the first `approach` of the run at the drawn speed.
    speed = spec["speed"]
    travel = speed * steps * dt * spec["approach"]
    if kind == "pair":
        d = _unit(spec["direction"])
        a, b = pieces
        ra = np.abs((a.pos - a.centroid) @ d).max() + a.material.radius
        rb = np.abs((b.pos - b.centroid) @ d).max() + b.material.radius
        lateral = spec["offset"] * min(sizes) * _perp(d, spec["offsetAngle"])
        _moveTo(a, -d * (ra + travel / 2), 0.5 * speed * d, spec["pieces"][0]["spin"])
        _moveTo(b, d * (rb + travel / 2) + lateral, -0.5 * speed * d, spec["pieces"][1]["spin"])
        # with a lateral offset curved faces meet later: close the gap between
        # the node sets along d to r_a + r_b + travel (never into overlap)
        target = a.material.radius + b.material.radius + travel
        for _ in range(6):
            gap = min(_surfaceDistance(a, b.pos), _surfaceDistance(b, a.pos)) - target
            if abs(gap) <= 1e-3 * target:
                break
            b.pos[:] -= gap * d
    elif kind == "drop":
        p = pieces[0]
        h = np.abs((p.pos - p.centroid) @ normal).max() + p.material.radius
        tang = _perp(normal, spec["offsetAngle"])
        dirn = _unit(-normal * math.cos(spec["incidence"]) + tang * math.sin(spec["incidence"]))
        _moveTo(p, normal * (h + travel * abs(dirn @ normal) + 1e-9 * h), speed * dirn,
                spec["pieces"][0]["spin"])
    else:
        p = pieces[0]
        _moveTo(p, np.zeros(3), np.zeros(3), spec["pieces"][0]["spin"])
        d = _unit(spec["direction"])
        reach = np.abs(p.pos @ d).max() + p.material.radius
        body = O.bodies[dynIds[0]]
        R = max(O.bodies[i].shape.radius for i in sphereIds)
        ext = max(np.linalg.norm(np.array(O.bodies[i].state.pos) - np.array(body.state.pos)) for i in sphereIds)
        c = d * (reach + R + ext + travel) + spec["offset"] * sizes[0] * _perp(d, spec["offsetAngle"])
        for _ in range(4):  # close the gap to the drawn travel (curved faces, offset)
            cs = np.array([list(O.bodies[i].state.pos) for i in sphereIds]) - np.array(body.state.pos) + c
            gap = _surfaceDistance(p, cs) - R - p.material.radius - travel
            if abs(gap) <= 1e-3 * (R + travel):
                break
            c = c - gap * d
        old = np.array(body.state.pos)
        for i in set(sphereIds) - {dynIds[0]}:  # clump members: moved with it now, not at YADE's next step
            O.bodies[i].state.pos = Vector3(*(np.array(O.bodies[i].state.pos) - old + c))
        body.state.pos = Vector3(*c)
        body.state.vel = Vector3(*(-speed * d))
        body.state.angVel = Vector3(*spec["spheres"]["spin"])
    O.dt = dt
    O.trackEnergy = True
    core = qe.world.core
    if "edgeFeatureAngle" in spec:  # a regression scene's own setting (default: QDEM's)
        core.edgeFeatureAngle = spec["edgeFeatureAngle"]

    def momentumNow():
        return sum(p.momentum for p in pieces) + _yadeMomentum(O, dynIds)

    conserveMomentum = kind in ("pair", "spheres")
    scaleP = float((np.abs(core.vel) * core.mass[:, None]).sum()) + sum(
        O.bodies[i].state.mass * np.linalg.norm(O.bodies[i].state.vel) for i in dynIds)
    before = {i: (np.array(O.bodies[i].state.vel), np.array(O.bodies[i].state.angVel)) for i in dynIds}
    state = {"e0": None, "p0": momentumNow(), "gravMax": 0.0, "k0": None, "passed": None, "mechMax": 0.0, "gained": None}

    def perStep():
        out.steps += 1
        pos, vel = core.pos, core.vel
        if not (np.isfinite(pos).all() and np.isfinite(vel).all()):
            out.fail("non-finite node state")
            O.pause()
            return
        e = core.energy
        ky = _yadeKinetic(O, dynIds, before)
        if state["e0"] is None:  # after the first step: the ledger starts when QDEM has booked it
            state["e0"] = e["total"] + ky
            state["k0"] = e["kinetic"] + ky
        mech = e["kinetic"] + ky + abs(e["elastic"]) + abs(e["contactElastic"])
        state["gravMax"] = max(state["gravMax"], abs(e["gravity"]))
        state["mechMax"] = max(state["mechMax"], mech)
        scale = state["mechMax"] + state["gravMax"] + 1e-300
        out.energyScale = scale
        gain = (e["total"] + ky - state["e0"]) / scale
        out.energyGain = max(out.energyGain, gain)
        if not math.isfinite(gain):
            out.fail("energy ledger not finite")
            O.pause()
            return
        if gain > EXPLOSION:
            out.fail("energy ledger exploded: gained %.3g of the energy in flight" % gain)
        if gain > ENERGY_GAIN * spec["dtFraction"] and state["gained"] is None:
            state["gained"] = (out.steps, "energy ledger gained %.3g of its scale (allowed %.3g)"
                               % (gain, ENERGY_GAIN * spec["dtFraction"]))
        if state["gained"] and out.steps - state["gained"][0] > qe.checkPeriod + 1:
            # the engine's current-shape check ran since and named nothing
            out.fail("%s at step %d; no named stop by step %d" % (state["gained"][1], state["gained"][0], out.steps))
        c = core.contactCounts
        out.contacted = out.contacted or (c["pointPolygon"] + c["edgeEdge"] + c["sphere"] + c["wall"]) > 0
        if conserveMomentum:
            dp = np.abs(momentumNow() - state["p0"]).max() / max(scaleP, 1e-300)
            out.momentumError = max(out.momentumError, dp)
            if dp > MOMENTUM_REL:
                out.fail("momentum changed by %.3g of sum m|v| with nothing external acting" % dp)
        if out.steps % PASS_CHECK == 0 and state["passed"] is None:
            msg = _passThrough(O, spec, pieces, normal, sphereIds)
            if msg:
                state["passed"] = (out.steps, msg)
        if state["passed"] and out.steps - state["passed"][0] > qe.checkPeriod + 1:
            # the engine checked since and named nothing: a silent pass
            out.fail("%s (at step %d; no named stop by step %d)" % (state["passed"][1], state["passed"][0],
                                                                   out.steps))
        if out.failure:
            O.pause()

    O.engines = O.engines + [PyRunner(command="import fuzzscene; fuzzscene._perStep()", iterPeriod=1)]
    global _perStep
    _perStep = perStep
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            O.run(steps, True)
        except Exception as e:  # noqa: BLE001 - classified in _stopped
            _stopped(out, e)
        finally:
            _perStep = None
    out.warnings = sorted({str(w.message)[:120] for w in caught})
    if out.failure is None and out.stop is None and state["gained"]:
        out.fail("%s at step %d; none named by the end of the run" % state["gained"][::-1])
    if out.failure is None and out.stop is None:
        msg = _passThrough(O, spec, pieces, normal, sphereIds)
        msg = msg or (state["passed"] and state["passed"][1])
        if msg:  # the engine's own checks, as at its next checkPeriod
            try:
                core.checkFinite()
                if core.nPieces > 1:
                    core.checkDeepOverlap()
                if core.nSpheres:
                    core.checkSpheresInside()
            except Exception as e:  # noqa: BLE001 - classified in _stopped
                _stopped(out, e)
            else:
                out.fail("%s (at the end of the run; no named stop)" % msg)
        if O.dt > stable * (1 + 1e-12):
            out.fail("O.dt %.6g above the stable step %.6g" % (O.dt, stable))
        try:
            after = qe.stableTimeStep()
        except Exception as e:  # noqa: BLE001 - classified in _stopped
            _stopped(out, e)
        else:
            if O.dt > after * (1 + 1e-12):
                out.fail("the stable step fell to %.6g during the run, below O.dt = %.6g, and nothing was "
                         "refused" % (after, O.dt))
        for p in pieces:
            if p.material.law == "saintVenantKirchhoff":
                v = qdem._core.tetVolumes(p.pos, p.tets)
                if (v <= 0).any():
                    out.fail("Saint-Venant-Kirchhoff piece %d left with %d inverted elements, no stop"
                             % (p.id, int((v <= 0).sum())))
    return out


_perStep = None


def _minDistance(x, y):
    d2 = ((x[:, None, :] - y[None, :, :]) ** 2).sum(axis=2)
    return float(np.sqrt(d2.min()))


def _pointTriangleDistance(P, A, B, C):
    """Distances (p,t) from points P (p,3) to triangles ABC (t,3 each):
    the closest point of each triangle by Voronoi region (Ericson, Real-Time
    Collision Detection, 5.1.5), vectorised."""
    P = P[:, None, :]
    ab, ac = (B - A)[None], (C - A)[None]
    ap, bp, cp = P - A[None], P - B[None], P - C[None]
    dot = lambda u, v: (u * v).sum(axis=-1)  # noqa: E731
    d1, d2, d3, d4, d5, d6 = dot(ab, ap), dot(ac, ap), dot(ab, bp), dot(ac, bp), dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = vb / denom
        w = vc / denom
        q = A[None] + ab * v[..., None] + ac * w[..., None]                          # face
        tab = np.clip(d1 / (d1 - d3), 0, 1)
        tac = np.clip(d2 / (d2 - d6), 0, 1)
        tbc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    qab = A[None] + ab * tab[..., None]
    qac = A[None] + ac * tac[..., None]
    qbc = B[None] + (C - B)[None] * tbc[..., None]
    A_, B_, C_ = np.broadcast_to(A[None], q.shape), np.broadcast_to(B[None], q.shape), np.broadcast_to(C[None], q.shape)
    regions = [
        (d1 <= 0) & (d2 <= 0), (d3 >= 0) & (d4 <= d3), (d6 >= 0) & (d5 <= d6),
        (vc <= 0) & (d1 >= 0) & (d3 <= 0), (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)]
    for mask, point in zip(reversed(regions), reversed([A_, B_, C_, qab, qac, qbc])):
        q = np.where(mask[..., None], point, q)
    return np.linalg.norm(P - q, axis=-1)


def _surfaceDistance(p, points):
    """Smallest distance from points (n,3) to piece p's surface triangles:
    what its point-polygon contacts measure."""
    x = p.pos[p.surface()["triangles"]]
    return float(_pointTriangleDistance(np.asarray(points, float), x[:, 0], x[:, 1], x[:, 2]).min())


def _moveTo(p, c, v, spin):
    x = p.pos
    c0 = p.centroid
    x += np.asarray(c) - c0
    p.vel[:] = np.asarray(v) + np.cross(np.asarray(spin, float), x - np.asarray(c))


def _surfaceSamples(p, n=4):
    """Points on the piece's surface triangles (a barycentric grid of n+1
    rows) and the largest distance from a surface point to its nearest
    sample (the sampling error of a depth measured on them)."""
    tri = p.surface()["triangles"]
    x = p.pos[tri]                                                # (t,3,3)
    w = np.array([(i, j, n - i - j) for i in range(n + 1) for j in range(n + 1 - i)], float) / n
    pts = np.einsum("kv,tvd->tkd", w, x).reshape(-1, 3)
    edge = np.linalg.norm(x - x[:, [1, 2, 0]], axis=2).max()
    return pts, edge / n


def _depthInside(points, p):
    """Per point: its distance below piece p's surface (0 when outside),
    measured on surface samples, less their sampling error: a lower bound."""
    inside = _pointsInside(points, p.pos, p.tets)
    if not inside.any():
        return np.zeros(len(points))
    pts, err = _surfaceSamples(p)
    d = np.sqrt(((points[:, None, :] - pts[None, :, :]) ** 2).sum(axis=2).min(axis=1)) - err
    return np.where(inside, np.maximum(d, 0.0), 0.0)


def _passThrough(O, spec, pieces, normal, sphereIds):
    """What has passed through what, or None: a piece's centroid or a sphere's
    centre deeper inside a piece than the contact's reach (r_a + r_b, R + r:
    beyond it nothing pushes it out), or a piece's centroid behind the wall
    it was thrown at."""
    kind = spec["kind"]
    if kind == "pair":
        a, b = pieces
        reach = a.material.radius + b.material.radius
        for i, (p, q) in enumerate(((a, b), (b, a))):
            if spec["pieces"][i]["mesh"]["convex"]:
                depth = _depthInside(p.centroid[None], q)[0]
                if depth > reach:
                    return ("the centroid of piece %d is %.3g m inside piece %d (beyond the contact reach %.3g m): "
                            "passed through it" % (p.id, depth, q.id, reach))
    elif kind == "drop":
        p = pieces[0]
        if p.centroid @ normal < 0:
            return ("piece 0's centroid is behind the %s it was thrown at: passed through it"
                    % spec["obstacle"]["kind"])
    else:
        p = pieces[0]
        c = np.array([list(O.bodies[i].state.pos) for i in sphereIds])
        R = np.array([O.bodies[i].shape.radius for i in sphereIds])
        depth = _depthInside(c, p)
        deep = depth > R + p.material.radius
        if deep.any():
            k = int(np.argmax(deep))
            return ("YADE sphere %d's centre is %.3g m inside piece 0 (beyond the contact reach %.3g m): passed "
                    "into it" % (sphereIds[k], depth[k], R[k] + p.material.radius))
    return None


def _stopped(out, e):
    name = type(e).__name__
    msg = str(e)
    if name not in NAMED_STOPS:
        out.fail("unexpected exception %s: %s" % (name, msg[:400]))
    elif name == "StabilityError" and "not finite" in msg:
        out.fail("blow-up below the stable step (named, but a NaN): %s" % msg[:400])
    elif len(msg) < 20:
        out.fail("%s without a message naming the problem: %r" % (name, msg))
    else:
        out.stop = "%s: %s" % (name, msg[:300])
    return out


# -------------------------------------------------------------- strategies ---

def sceneSpecs():
    """Hypothesis strategy of scene specs."""
    from hypothesis import strategies as st

    logu = lambda lo, hi: st.floats(math.log10(lo), math.log10(hi)).map(lambda x: 10.0 ** x)  # noqa: E731
    unitVec = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: 0.1 < np.linalg.norm(v))

    def box():
        return st.builds(lambda s, c, t: {"kind": "box", "size": list(s), "cells": list(c), "tetsPerCell": t,
                                          "convex": True},
                         st.tuples(*[logu(0.02, 0.2)] * 3).filter(lambda s: max(s) / min(s) < 6),
                         st.tuples(*[st.integers(1, 3)] * 3), st.sampled_from([5, 6, 12]))

    mesh = st.one_of(
        box(),
        st.builds(lambda r, n, s: {"kind": "ball", "size": r, "cellsPerRadius": n, "seed": s, "convex": True},
                  logu(0.02, 0.1), st.sampled_from([1.5, 2.5]), st.integers(0, 1)),
        st.builds(lambda k, r, c: {"kind": "cgal", "shape": k, "size": r, "cellSize": c, "seed": 0,
                                   "convex": True},
                  st.sampled_from(["prism", "octahedron", "ellipsoid"]), logu(0.02, 0.1),
                  st.sampled_from([0.5, 0.8])),
        st.builds(lambda k, r, a: {"kind": "tetgen", "shape": k, "size": r, "maxVolume": a, "convex": True},
                  st.sampled_from(["ball", "prism"]), logu(0.02, 0.1), st.sampled_from([0, 0.05])))
    material = st.fixed_dictionaries({
        "young": logu(1e5, 1e10), "poisson": st.floats(-0.5, 0.49), "density": logu(300, 10000),
        "xi": st.one_of(st.just(0.0), logu(1e-3, 3.0)), "restitution": st.floats(0.05, 1.0),
        "friction": st.floats(0, 1), "radiusFraction": logu(0.05, 1.0),
        "law": st.sampled_from(["stableNeoHookean", "saintVenantKirchhoff"])})
    spin = st.tuples(*[st.floats(-20, 20)] * 3)
    piece = st.fixed_dictionaries({"mesh": mesh, "material": material, "oriAxis": unitVec,
                                   "oriAngle": st.floats(0, math.pi), "spin": spin})
    common = {"threads": st.sampled_from([1, 1, 1, 2]), "dtFraction": st.floats(0.3, 0.95),
              "steps": st.integers(200, 1500), "speed": st.floats(0.1, 30.0), "approach": st.floats(0.0, 0.4),
              "offset": st.floats(0, 0.3), "offsetAngle": st.floats(0, 2 * math.pi)}
    pair = st.fixed_dictionaries(dict(common, kind=st.just("pair"), gravity=st.just(False),
                                      pieces=st.lists(piece, min_size=2, max_size=2), direction=unitVec))
    obstacle = st.one_of(
        st.fixed_dictionaries({"kind": st.just("wall"), "axis": st.integers(0, 2), "sense": st.sampled_from([-1, 1]),
                               "frictionAngle": st.floats(0, 1)}),
        st.fixed_dictionaries({"kind": st.sampled_from(["facets", "box"]), "frictionAngle": st.floats(0, 1)}))
    drop = st.fixed_dictionaries(dict(common, kind=st.just("drop"), gravity=st.booleans(),
                                      pieces=st.lists(piece, min_size=1, max_size=1), obstacle=obstacle,
                                      incidence=st.floats(0, 1.2)))
    spheres = st.fixed_dictionaries(dict(
        common, kind=st.just("spheres"), gravity=st.just(False), pieces=st.lists(piece, min_size=1, max_size=1),
        direction=unitVec,
        spheres=st.fixed_dictionaries({"clump": st.booleans(), "radiusFraction": logu(0.05, 0.5),
                                       "young": logu(1e5, 1e10), "density": logu(300, 10000),
                                       "frictionAngle": st.floats(0, 1), "spin": spin})))
    return st.one_of(pair, drop, spheres)
