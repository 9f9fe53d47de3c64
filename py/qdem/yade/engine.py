"""QdemEngine: advances the QDEM world inside YADE's loop.

Place it after ForceResetter and before NewtonIntegrator::

    O.engines = [ForceResetter(), ..., QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81))]

Each YADE step it reads the walls/boxes/facets, gravity and O.dt, steps the
QDEM nodes with the same leapfrog as NewtonIntegrator (so both advance on one
clock), writes the walls' reactions into O.forces and the QDEM energies into
O.energy (when O.trackEnergy is on).  It is a PyRunner: the per-step cost of
the Python glue is a few microseconds plus a few per obstacle."""
import math
import time
import warnings
import weakref

import numpy as np
from yade import O, PyRunner

from .. import _core, meshchecks
from ..attrs import Attr, AttrObject, WorldSetting, boolean, documented, integer, number, worldSettings
from ..mpi import ranks as parallel
from ..world import FollowsDefaultWorld
from . import glue as yadeglue
from . import lifecycle, setupcheck
from . import mpy as mpyglue
from .enginemeta import EngineMeta
from .recorder import initialFrames
from .spheres import SphereCoupling

_NO_SPHERES = [np.zeros(0, np.int32)] + [np.zeros(0)] * 6 + [np.zeros(1, np.int32), np.zeros(0, np.int32)]

ENERGY_KEYS = {"kinetic": "qdemKinetic", "elastic": "qdemElastic", "gravity": "qdemGravWork",
               "viscous": "qdemViscDissip", "contactElastic": "qdemContactElastic",
               "contactDamping": "qdemContactDamp", "friction": "qdemFrictDissip",
               "boundaryWork": "qdemBoundaryWork", "localDamping": "qdemNonviscDamp", "sleep": "qdemSleep",
               "rigid": "qdemRigid"}


def _shapeNames(v):
    """Validator of QdemEngine.ignoreShapes: a list of shape class names."""
    if not isinstance(v, (list, tuple)) or not all(isinstance(x, str) for x in v):
        return "a list of YADE shape class names, e.g. ['Polyhedra'] (not %r)" % (v,)
    return None


@lifecycle.savedWithScene
@documented
class QdemEngine(FollowsDefaultWorld, PyRunner, metaclass=EngineMeta):
    """Steps the QDEM world each YADE iteration.  Keyword construction as for any
    YADE engine: ``QdemEngine(label='qe', progressPeriod=1000)``; ``world=`` picks
    a qdem.World other than qdem.defaultWorld().  Place it after ForceResetter
    (and after InsertionSortCollider/InteractionLoop when YADE spheres share the
    scene) and before NewtonIntegrator, which it reads gravity from; wrong
    orders are refused at the first step (doc/yade.md).

    An engine without ``world=`` acts on the default world: kept across
    ``O.reset()``, it steps the new scene's pieces with its own settings.

    ``engine.inverted`` counts inverted elements (volume ratio <= 0), checked
    every checkPeriod steps: ``now``, ``max`` (the largest count seen), ``time``
    (how long any element was inverted [s]), ``first`` (piece, element, volume
    ratio of the latest episode).  A law that cannot push an inverted element
    back (law='saintVenantKirchhoff') stops the run with qdem.StabilityError."""

    checkDt = Attr(True, "Refuse to step when O.dt is above the stable time step "
                         "(raises qdem.StabilityError naming the limit).", boolean)
    checkPeriod = Attr(100, "Every this many steps, count inverted elements (see inverted) and (with "
                            "checkDt) check that O.dt is below the stable step of the current, strained "
                            "shape, and that no surface node lies inside another piece deeper than their "
                            "contact reach r_a + r_b where no contact sees it (qdem.StabilityError naming "
                            "them: contacts too soft for the load; doc/hard_cases.md, 'Deep overlap'), and "
                            "(with O.trackEnergy) the energy ledger (energyDrift) (0 = never).  A node a "
                            "contact holds deeper than the reach stops the step it happens.  Non-finite positions and velocities are caught every "
                            "step regardless: the step that meets one raises qdem.StabilityError.",
                        integer(0, extra=" (0 = never)"))
    energyDrift = Attr(0.1, "With O.trackEnergy: every checkPeriod steps the QDEM energy ledger (the sum of "
                            "its qdem* terms, dissipation and work included) is compared with its value at the "
                            "first check; a drift beyond this fraction of the largest energy it has held (the "
                            "sum of the terms' magnitudes) warns once (RuntimeWarning naming the drift and its "
                            "likely causes; doc/hard_cases.md, 'Energy ledger').  Correct runs drift by the "
                            "scheme's first-order error: up to 4 % in impacts at 0.8 of the stable step (the "
                            "dashpots' first steps), 0.5 % at 0.2 of it (0 = not checked; not with YADE spheres, "
                            "whose side of the exchange is YADE's ledger).", number(0, 1))
    progressPeriod = Attr(0, "Print a progress line every this many steps (0 = silent).",
                          integer(0, extra=" (0 = silent)"))
    threads = Attr(0, "OpenMP threads for QDEM (0 = YADE's own count, from yade -j).  YADE keeps its "
                      "own count either way.", integer(0, extra=" (0 = YADE's own count)"))
    sphereMask = Attr(-1, "groupMask of the proxy bodies that find spheres near pieces: only spheres "
                          "whose mask shares a bit with it touch QDEM pieces (-1 = all).",
                      integer(-2**31, 2**31 - 1, extra=" (a YADE groupMask; -1 = all)"))
    gatherPeriod = Attr(1, "Under MPI (doc/parallel.md): every this many steps every rank learns every node's "
                           "position, velocity and force, so that scripts, recorders and checks read them as "
                           "serially (0 = only before checks).  Larger is faster; piece arrays read between "
                           "gathers raise an error instead of giving stale values.  No effect on one process.",
                        integer(0, extra=" (0 = only before checks)"))
    sphereMargin = Attr(0.1, "Proxy boxes are the pieces' boxes grown by this fraction of their size: "
                             "larger = fewer proxy moves (each forces a collider run), more spheres read.",
                        number(0.01, 10))
    ignoreShapes = Attr((), "Names of YADE shape classes whose bodies QDEM pieces may pass through, e.g. "
                            "['Polyhedra'] for grains that never reach a piece.  A body of any other shape "
                            "pieces cannot collide with (anything but Wall, Box, Facet, Sphere) stops the run "
                            "at the first step with qdem.SetupError: a piece would fall through it unseen.",
                        _shapeNames, tuple)
    # The world settings (viscosity, damping, friction, contact kinds, sleeping, ...):
    # declared once in pkg/step/Settings.hpp; read and written on the world directly.
    worldSettings(locals())

    _yadeAttrs = ("label", "dead")   # YADE's own Engine attributes it takes as keywords
    _public = ("stableDt", "stableTimeStep", "proxyIds", "bodiesChanged", "sphereCouplingTime", "stepOnce",
               "dict")

    def __init__(self, world=None, qdemId=None, **kw):
        PyRunner.__init__(self)
        known = AttrObject.attrNames.__func__(type(self))
        for k in kw:
            if k not in self._yadeAttrs and k not in known:
                raise TypeError("QdemEngine: unknown keyword %r; known: world, label, dead, %s"
                                % (k, ", ".join(known)))
        self._setWorld(world)
        # A new engine starts from the declared defaults (as YADE engines start
        # from theirs), then takes the keywords.  They go into the world at
        # once unless another live engine steps it (two engines, one dead; a
        # throw-away QdemEngine() made to read a stable step: they reset the
        # running one's settings, found by a tester): then when this engine
        # first steps or computes a stable step (_activate).
        self._own = {}
        self._owner = False
        for k in known:
            a = getattr(type(self), k)
            if isinstance(a, WorldSetting):
                self._own[k] = a.default
        current = getattr(self._world, "_settingsOwner", None)
        current = current() if current is not None else None
        if current is None and not kw.get("dead", False):
            self._activate()
        for k, v in kw.items():
            setattr(self, k, v)
        self.iterPeriod = 1
        self.initRun = True
        self.qdemId = qdemId or lifecycle.newId()
        # The command names the engine by an id that YADE saves with the scene:
        # after O.load the engine is rebuilt from O.tags['qdem'] (lifecycle.py).
        self.command = "import qdem.yade.engine; qdem.yade.engine._step('%s')" % self.qdemId
        self._freshRunState()

    def _ownsSettings(self):
        """Are this engine's settings the ones in its world (it steps it)?"""
        if not self._owner:
            return False
        o = getattr(self.world, "_settingsOwner", None)
        return o is not None and o() is self

    def _activate(self):
        """Make this engine's settings the world's (it is about to step it, or
        to compute its stable step): the engine that held them keeps its own."""
        w = self.world
        o = getattr(w, "_settingsOwner", None)
        o = o() if o is not None else None
        if o is self and self._owner:
            return
        if o is not None and o is not self:
            o._own = {k: getattr(o, k) for k in o._own}  # (its values, direct changes to the core included)
            o._owner = False
        for k, a in ((k, getattr(type(self), k)) for k in self._own):
            v = self._own[k]
            if a.decl["kind"] == "choice":
                v = a.decl["choices"].index(v)
            setattr(w.core, a.decl["name"], v)
        w._settingsOwner = weakref.ref(self)
        self._owner = True

    def _freshRunState(self):
        """What the engine learns of its scene while it runs (none of it a setting)."""
        self._checkedSetup = None
        self._lastStepAt = None
        self._warnedDamping = False
        self._warnedTurning = False
        self._posDriven = yadeglue.PosDrivenWatch()
        self._syncForces = False  # a force-reading engine follows (setupcheck._checkForceReaders)
        self._runStart = None
        self._nBodies = -1
        self._unfelt = []  # (id, shape) of the bodies pieces cannot collide with, at the last scan
        self._ids, self._states, self._signatures, self._obstacles = [], None, [], []
        self._dtChecked = None
        self._dtNoted = None          # the step key YADE's default O.dt was last weighed at
        self._warnedDefaultDt = False
        self._lastProgress = None
        self._ledger = None  # the energy ledger at its reference check (_checkLedger)
        #: Inverted elements (volume ratio <= 0), counted every checkPeriod: ``now`` (at the last
        #: check), ``max`` (largest count seen), ``time`` [s] (time during which any element
        #: was inverted, to one checkPeriod), ``first`` (piece, element, volume ratio) of the
        #: latest episode.  Only laws that push inverted elements back get here: with
        #: law='saintVenantKirchhoff' an inversion stops the run with qdem.StabilityError.
        self.inverted = {"now": 0, "max": 0, "time": 0.0, "first": None}
        self._lastCheckTime = None
        #: Box and Facet edge-triangle crossings found at the last check (an obstacle edge
        #: that passed between a piece's surface nodes; a warning names the first).
        self.edgeCrossings = 0
        self._warnedEdges = set()
        self._spheres = None  # SphereCoupling, once a sphere is seen
        self._sphereVersion = None
        self._mpy = None      # MpyCoupling under yade.mpy (mpy.py)
        self._obstacleLink, self._sphereLink, self._mpyLink = _Obstacles(self), _Spheres(self), _Mpy(self)

    def _worldReplaced(self, old, new):
        """O.reset() replaced the default world: the new one takes this engine's
        settings (they live in the world), and the engine forgets the old scene.
        A world that O.load rebuilt keeps the loaded scene's settings: this
        engine is not one of that scene's (O.load put its own in O.engines),
        and a script touching its old engine object must not change them."""
        o = getattr(old, "_settingsOwner", None)
        if self._owner and o is not None and o() is self:  # its values, direct changes to the core included
            for k in self._own:
                a = getattr(type(self), k)
                v = getattr(old.core, a.decl["name"])
                self._own[k] = a.decl["choices"][v] if a.decl["kind"] == "choice" else v
        self._owner = False
        if not getattr(new, "_restored", False) and getattr(new, "_settingsOwner", None) is None:
            self._activate()
        self._freshRunState()

    def __repr__(self):
        return "<QdemEngine%s at %#x>" % (" %r" % self.label if self.label else "", id(self))

    # -- public helpers --------------------------------------------------------
    def dict(self):
        """QDEM's settings of this engine as a plain dict (like YADE's Serializable.dict())."""
        return {k: getattr(self, k) for k in AttrObject.attrNames.__func__(type(self))}

    def stableDt(self):
        """Stable time step (dict: elastic, viscous, contact, combined, limitedBy), with the
        current YADE obstacles included.  combinedExplicit and combinedImplicit are the
        combined limit with the viscous force integrated explicitly and implicitly
        (viscousIntegration); combined is the one in force.  piece, elements,
        elementsNearLimit, worstQuality, medianElastic, medianViscous,
        medianFactorElastic, medianFactorViscous and elementLimit name what in the
        element step sets it (see qdem.World.stableDt)."""
        self._activate()  # this engine's settings decide its stable step
        if self._mpy is None:  # (under yade.mpy the step's allgather set them, alike on every rank)
            self._syncObstacles()
            if self._spheres is not None and self.spheres:
                self._spheres.listAll(O)  # any sphere may come near: bound them all
        return self.world.core.stableDt()

    def stableTimeStep(self):
        """The largest O.dt [s] QDEM accepts in this scene (a number, as YADE's
        utils.PWaveTimeStep()): stableDt()['combined'].  A scene where no step is
        stable (a dynamic body of zero mass) raises, naming it (O.dt = 0.8 * 0
        failed at the first step with a message that named nothing)."""
        d = self.stableDt()
        dt = float(d["combined"])
        if not dt > 0:
            raise _core.StabilityError(
                "QdemEngine.stableTimeStep(): no time step is stable in this scene: it is limited by %s, which "
                "allows none. A dynamic YADE body of zero mass or moment of inertia (YADE's facets have none) "
                "cannot be integrated: make it fixed (utils.facet(..., fixed=True), or body.dynamic = False) or "
                "give it a mass and an inertia%s" % (d.get("limitedBy", "?"), "; the smallest element steps: "
                                                       + d["elementLimit"] if d.get("elementLimit") else ""))
        return dt

    # -- save / load (lifecycle.py) ------------------------------------------------
    def savedState(self):
        """What O.save keeps of this engine besides its PyRunner fields."""
        sp = self._spheres
        return {"kind": "QdemEngine", "settings": self.dict(), "label": self.label, "dead": bool(self.dead),
                "inverted": dict(self.inverted), "lastCheckTime": self._lastCheckTime,
                "proxies": list(sp.proxies) if sp is not None else [],
                "proxyBox": [[list(map(float, lo)), list(map(float, hi))] for lo, hi in sp.proxyBox]
                if sp is not None else []}

    @classmethod
    def fromSaved(cls, qdemId, st, runner=None):
        """The engine of a loaded scene, from savedState()."""
        e = cls(qdemId=qdemId, **lifecycle.savedSettings(st["settings"]))
        e.label, e.dead = st.get("label", ""), st.get("dead", False)
        if st.get("inverted"):
            e.inverted = dict(st["inverted"])
            e.inverted["first"] = tuple(e.inverted["first"]) if e.inverted.get("first") else None
        e._lastCheckTime = st.get("lastCheckTime")
        if st.get("proxies"):
            e._spheres = SphereCoupling(e.world, int(e.sphereMask), float(e.sphereMargin))
            e._spheres.adopt(st["proxies"], st["proxyBox"])
        return e

    def proxyIds(self):
        """Ids of the proxy bodies (one non-dynamic wire Tetra per piece) through which
        YADE's collider finds the spheres near each piece; skip them in loops over
        O.bodies that expect only your own bodies."""
        return list(self._spheres.proxies) if self._spheres is not None else []

    def bodiesChanged(self):
        """Call after erasing bodies and appending others in the same step (YADE may
        reuse the ids): the engine scans O.bodies again at its next step."""
        self._nBodies = -1

    def sphereCouplingTime(self):
        """Wall time [s] spent so far on coupling with YADE spheres: lists, states,
        sphere-surface contacts, forces back to O.forces (for benchmarks)."""
        return (self._spheres.seconds if self._spheres is not None else 0.0) + \
            (self._mpy.seconds if self._mpy is not None else 0.0)

    def stepOnce(self):
        """One QDEM step at O.dt without YADE's loop (for tests and debugging)."""
        self._run()

    # -- the step --------------------------------------------------------------
    def _syncObstacles(self):
        core = self.world.core
        if not self.couple:
            if core.nObstacles:
                core.setObstacles([])
            self._ids, self._unfelt = [], []  # (couple=False: the script asked for no obstacles)
            self._nBodies = -1  # (couple=True again: scan O.bodies anew)
            return
        if len(O.bodies) != self._nBodies:
            self._unfelt = yadeglue.unfeltBodies(O)  # (refused by the step, not by stableTimeStep)
            obstacles, self._ids = yadeglue.scanObstacles(O)
            self._obstacles = obstacles
            self._signatures = [yadeglue.bodySignature(O.bodies[i]) for i in self._ids]
            if self.spheres and self._spheres is None and yadeglue.hasSpheres(O):
                self._spheres = SphereCoupling(self.world, int(self.sphereMask), float(self.sphereMargin))
            if self._spheres is not None:
                self._spheres.bodiesChanged()
            core.setObstacles(obstacles)
            self._states = np.zeros((len(self._ids), 16))
            self._seen = [None] * len(self._ids)  # (obstacleStates: what the rows were written from)
            self._nBodies = len(O.bodies)
        if self._ids:
            reshaped, written = [], []
            states = yadeglue.obstacleStates(O, self._ids, self._states, self._signatures, reshaped, self._seen,
                                             written)
            if states is None:  # a body was erased (O.bodies keeps its length): scan again
                self._nBodies = -1
                return self._syncObstacles()
            if reshaped:
                # A Box's extents or a Facet's vertices were changed by the script, a body was
                # made dynamic or fixed (its mass enters the stable step and the dashpots), or
                # the body is another one now: those obstacles are rebuilt; contacts keep their history.
                bodies = [O.bodies[self._ids[i]] for i in reshaped]
                rebuilt, rebuiltIds = yadeglue.scanObstacles(O, bodies)
                if rebuiltIds != [self._ids[i] for i in reshaped]:  # no longer an obstacle: scan all
                    self._nBodies = -1
                    return self._syncObstacles()
                for i, o, b in zip(reshaped, rebuilt, bodies):
                    self._obstacles[i] = o
                    self._signatures[i] = yadeglue.bodySignature(b)
                core.setObstacles(self._obstacles)
                self._seen = [None] * len(self._ids)
                states = yadeglue.obstacleStates(O, self._ids, self._states, seen=self._seen, written=written)
            self._posDriven.watch(O, self._ids, states, bool(written))
            core.setObstacleStates(states)

    def _couplings(self):
        """This step's couplings with YADE, in order: each takes YADE's state into QDEM
        before the step (beforeStep(O)) and QDEM's forces into O.forces after it
        (afterStep(O)).  Under yade.mpy one, gathering obstacles and spheres from
        their owners (mpy.py); else the walls, boxes and facets, then the spheres."""
        if self._mpy is not None:
            return (self._mpyLink,)
        return (self._obstacleLink, self._sphereLink)

    def _run(self):
        core = self.world.core
        # How long a step lasts (lifecycle._settle waits for one in flight):
        # between two consecutive steps of one O.run, not across the script's
        # own work between runs.
        now, at = time.perf_counter(), (O.iter, O.stopAtIter)
        if self._lastStepAt is not None and self._lastStepAt[1] == (at[0] - 1, at[1]):
            lifecycle.stepSeconds = now - self._lastStepAt[0]
        self._lastStepAt = (now, at)
        if not self._owner:  # (another engine's settings were in force: this one's now)
            self._activate()
        if self.iterPeriod != 1:  # (read every step: set mid-run, it would slow QDEM's clock at once)
            setupcheck.checkPeriods(self)
        if self._checkedSetup != O.iter:  # first step of a run, and every checkPeriod
            if self._checkedSetup is None or (self.checkPeriod and O.iter % self.checkPeriod == 0) \
                    or O.iter < (self._checkedSetup or 0):
                setupcheck.check(self, O)
            self._checkedSetup = O.iter
        stop = O.stopAtIter  # a new O.run(n): remember where it started (progress share and ETA)
        if self._runStart is None or self._runStart[1] != stop:
            self._runStart = (O.iter, stop, core.iter, time.time())
        if self.threads:
            _core.setThreads(int(self.threads))
        mp = mpyglue.module() if getattr(O, "splitted", False) else None  # (set by yade.mpy's split)
        if mp is not None and self._mpy is None:
            self._mpy = mpyglue.MpyCoupling(self.world, mp, float(self.sphereMargin))
        elif mp is None and self._mpy is not None:
            # mpy merged the scene (mergeScene, mpirun(withMerge=True)): a rank
            # stepping alone would wait forever in QDEM's collectives.
            raise RuntimeError("qdem: under yade.mpy QDEM steps only inside mp.mpirun, on every rank; this scene "
                               "was merged (mp.mergeScene or withMerge=True): read it, or call mp.mpirun again "
                               "(doc/parallel.md, 'Under yade.mpy')")
        g = yadeglue.findGravity(O)
        if not all(math.isfinite(x) for x in g):
            raise ValueError("QdemEngine: NewtonIntegrator.gravity = %s is not finite: set a finite gravity "
                             "vector" % (tuple(g),))
        core.gravity = g
        core.trackEnergy = bool(O.trackEnergy)
        couplings = self._couplings()
        for c in couplings:  # YADE's state into QDEM
            c.beforeStep(O)
        dt = O.dt
        # O.dt is checked again when it or anything the stable step depends on changed (the core's version)
        key = (dt, core.stableStepVersion)
        if self.checkDt and self._dtChecked != key:
            core.checkDt(dt)
            self._dtChecked = key
        if dt == setupcheck.YADE_DEFAULT_DT and not self._warnedDefaultDt and self._dtNoted != key:
            setupcheck.noteDefaultDt(self, O, dt)
            self._dtNoted = key
        if core.mpiSize == 1 and self._mpy is not None:
            mpyglue.attach(self.world)  # split over mpy's ranks (collective: every rank runs this engine)
        elif core.mpiSize == 1 and parallel.launchedSize() > 1:
            parallel.attach(self.world)  # split across the ranks (collective: every rank runs this engine)
        if core.iter == 0 and core.time == 0.0:
            # A world's first step: its clock starts at YADE's (the engine may
            # join a scene that has run), so frames are named by O.iter and
            # timed by O.time; then the frame of the initial state.
            core.iter, core.time = int(O.iter), float(O.time)
            initialFrames(self.world)
        elif getattr(self.world, "_stepMark", None) is not None and self._mpy is None:
            # YADE made steps this engine did not (it was dead, or out of
            # O.engines) while nothing else moved QDEM's clock (a
            # qdem.loadState would have): the pieces stood still meanwhile.
            # QDEM's clock skips the missed steps, so that frames stay named
            # by O.iter and timed by O.time.
            yadeIter, yadeTime, coreIter = self.world._stepMark
            missed = int(O.iter) - yadeIter
            if missed > 0 and core.iter == coreIter:
                warnings.warn("QdemEngine did not run in the %d steps before O.iter = %d (dead=True, or out of "
                              "O.engines): the QDEM pieces stood still meanwhile, while YADE's bodies moved on. "
                              "QDEM's clock jumps from step %d (t = %.6g s) by those steps (%.6g s). To hold "
                              "pieces still, block their nodes (piece.blocked) instead of stopping the engine."
                              % (missed, O.iter, core.iter, core.time, float(O.time) - yadeTime), RuntimeWarning,
                              stacklevel=3)
                core.iter, core.time = core.iter + missed, core.time + (float(O.time) - yadeTime)
        try:
            core.step(dt)
        except ValueError as e:  # (InputError) a piece started inside an obstacle: say when its mesh looks like mm
            explained = meshchecks.explainRefusal(self.world, e)
            if explained is None:
                raise
            raise type(e)(explained) from None
        # Where YADE's next step starts, and QDEM's step now: kept with the
        # world, so that a new engine on it notices steps none made.
        self.world._stepMark = (int(O.iter) + 1, float(O.time) + dt, core.iter)
        for c in couplings:  # QDEM's forces into O.forces
            c.afterStep(O)
        if self._syncForces and len(O.bodies):
            # A ServoPIDController follows and reads O.forces, which YADE
            # 2023.02a refuses unsynchronised after addF (setupcheck._checkForceReaders).
            O.forces.f(0, sync=True)
        if core.trackEnergy:
            for k, v in core.energy.items():
                if k in ENERGY_KEYS:
                    O.energy[ENERGY_KEYS[k]] = v
        for msg in core.takeStartWarnings():  # pieces placed pressed into an obstacle: at once (they are thrown)
            warnings.warn(msg, RuntimeWarning, stacklevel=3)
        # The checks due at this step, scheduled and run by the core (every checkPeriod steps;
        # under MPI every node gathered first, and every gatherPeriod steps for the scripts).
        checked = core.periodicChecks(int(self.checkPeriod), int(self.gatherPeriod), dt, bool(self.checkDt))
        if checked is not None:
            self._noteInverted(core, dt, checked["inverted"])
            if core.nObstacles and core.nPieces:
                self._noteObstacleEdges(core, checked["edges"])
            if core.trackEnergy and self.energyDrift > 0 and not core.nSpheres:
                self._checkLedger(core)
        if self.progressPeriod and core.iter % self.progressPeriod == 0:
            counts = parallel.summedCounts(core)  # (collective under MPI: every rank gets here)
            if parallel.isWriter():
                self._progress(core, counts)

    def _checkLedger(self, core):
        """The energy ledger's imbalance, a checked quantity: its total (every term, dissipation and
        work included) must stay where it was at the first check, to the scheme's first-order drift
        (doc/hard_cases.md, 'Energy ledger').  A new piece, a loaded state, a rewound clock or a
        script that took a piece's writable pos, vel (or other node) array starts it afresh.  Warns
        once per drift, then follows from there."""
        e = core.energy
        total = sum(e[k] for k in ENERGY_KEYS if k in e)
        scale = sum(abs(e[k]) for k in ENERGY_KEYS if k in e)
        led = self._ledger
        edited = getattr(self.world, "_stateEdited", False)
        self.world._stateEdited = False
        if led is None or edited or led["pieces"] != core.nPieces or core.iter < led["iter"]:
            self._ledger = dict(ref=total, peak=scale, pieces=core.nPieces, iter=core.iter, since=core.iter)
            return
        led["peak"], led["iter"] = max(led["peak"], scale), core.iter
        drift = total - led["ref"]
        if abs(drift) <= self.energyDrift * led["peak"]:
            return
        warnings.warn(
            "QDEM: the energy ledger has %s %.4g J (%.3g %% of the largest energy it held, %.4g J) since step "
            "%d, beyond energyDrift = %g: the run is not conserving energy to the scheme's accuracy, so its "
            "result is in doubt. Likely causes: contacts or elements near their stability limit (a smaller "
            "O.dt; see QdemEngine.stableDt()), pieces sunk into each other or into obstacles (a stiffer "
            "contact or a larger radius), or a script that changed piece velocities, positions or masses "
            "between steps (the ledger sees that as energy from nowhere). O.energy holds the terms "
            "(doc/hard_cases.md, 'Energy ledger')."
            % ("lost" if drift < 0 else "gained", abs(drift), 100 * abs(drift) / led["peak"], led["peak"],
               led["since"], self.energyDrift),
            RuntimeWarning, stacklevel=4)
        self._ledger = dict(ref=total, peak=scale, pieces=core.nPieces, iter=core.iter, since=core.iter)

    def _noteObstacleEdges(self, core, c):
        """Warns (once per obstacle and piece) when a Box or Facet edge has passed
        between a piece's surface nodes (c: what the core's check found): pieces
        feel obstacles at their nodes only, so such an edge cuts into the piece
        unresisted."""
        self.edgeCrossings = c["count"]
        if not c["count"]:
            return
        key = (c["bodyId"], c["piece"])
        if key in self._warnedEdges:
            return
        self._warnedEdges.add(key)
        if parallel.isWriter():
            kind = ("wall", "box", "facet")[self._obstacles[c["obstacle"]].kind] \
                if c["obstacle"] < len(self._obstacles) else "obstacle"
            warnings.warn("QdemEngine: at step %d an edge of YADE body %d (%s) has passed between the surface nodes "
                          "of piece %d, near %s (%d edge-triangle crossings in all). QDEM pieces feel obstacles at "
                          "their nodes only (radius %g m), so an edge or corner narrower than the node spacing cuts "
                          "into them unresisted, and the forces are wrong from here on. Refine the piece's mesh "
                          "there, give it a larger radius, or make the obstacle wider than the node spacing "
                          "(doc/hard_cases.md, 'Known limits')."
                          % (core.iter, c["bodyId"], kind, c["piece"], tuple(round(x, 6) for x in c["point"]),
                             c["count"], self.world.pieces[c["piece"]].material.radius), RuntimeWarning, stacklevel=3)

    def _noteInverted(self, core, dt, r):
        # r: the core's count of inverted elements (it raised StabilityError, naming piece,
        # element, volume ratio and fix, for a law that cannot push them back).
        inv, n = self.inverted, r["count"]
        since = core.time - self._lastCheckTime if self._lastCheckTime is not None else self.checkPeriod * dt
        self._lastCheckTime = core.time
        if n:
            inv["time"] += since  # inverted at this check: counted for the whole period before it
            if not inv["now"] and parallel.isWriter():
                inv["first"] = (r["piece"], r["element"], r["volumeRatio"])
                warnings.warn("qdem: at t=%.6g s (step %d) %d element(s) inverted, the first tetrahedron %d of "
                              "piece %d (volume ratio %.3g); the material law pushes them back "
                              "(QdemEngine.inverted counts them)."
                              % (core.time, core.iter, n, r["element"], r["piece"], r["volumeRatio"]),
                              RuntimeWarning, stacklevel=2)
        elif inv["now"] and parallel.isWriter():
            print("qdem: at t=%.6g s (step %d) all inverted elements have recovered (at most %d, inverted for "
                  "%.3g s in all)" % (core.time, core.iter, inv["max"], inv["time"]), flush=True)
        inv["now"] = n
        inv["max"] = max(inv["max"], n)

    def _progress(self, core, c):
        # The QDEM clock (core.iter, core.time): it goes on across restarts,
        # where O.iter and O.time start again from 0.  The share done and the
        # time left come from O.run's target (O.stopAtIter) when it has one.
        now = time.time()
        line = "qdem: step %d  t=%.6g s" % (core.iter, core.time)
        rate = None
        start, stop, iter0, wall0 = self._runStart
        last = self._lastProgress
        if last is None or last[0] < iter0:  # the first line of this O.run: the rate since it started
            last = (iter0, wall0)
        if core.iter > last[0]:
            rate = (core.iter - last[0]) / max(now - last[1], 1e-9)
            line += "  %.0f steps/s" % rate
        self._lastProgress = (core.iter, now)
        if stop > 0 and stop > O.iter:
            done = (O.iter + 1 - start) / max(stop - start, 1)
            line += "  %3.0f%%" % (100 * min(done, 1.0))
            if rate:
                line += "  ETA %s" % _duration((stop - O.iter - 1) / rate)
        line += "  %d contacts (%d piece-piece, %d sphere, %d wall)" % (
            c["pointPolygon"] + c["edgeEdge"] + c["sphere"] + c["wall"], c["pointPolygon"] + c["edgeEdge"],
            c["sphere"], c["wall"])
        if core.sleepVelocity > 0:
            line += "  %d/%d pieces asleep" % (core.nAsleep, core.nPieces)
        if self.inverted["max"]:
            line += "  %d inverted (max %d, for %.3g s)" % (self.inverted["now"], self.inverted["max"],
                                                          self.inverted["time"])
        if core.trackEnergy:  # energies are only summed when O.trackEnergy is on
            e = core.energy
            line += "  E_kin=%.4g J  E_el=%.4g J" % (e["kinetic"], e["elastic"])
        print(line, flush=True)


class _Obstacles:
    """The coupling with YADE's walls, boxes and facets: their states into QDEM
    before the step (scanned again when O.bodies changes), their reactions into
    O.forces after it."""

    def __init__(self, engine):
        self.engine = engine

    def beforeStep(self, O):
        e = self.engine
        e._syncObstacles()
        if any(name not in e.ignoreShapes for _, name in e._unfelt):
            # (scanned when O.bodies grew: scanned again, as an erased one keeps its length)
            e._unfelt = yadeglue.unfeltBodies(O)
            unfelt = [(i, name) for i, name in e._unfelt if name not in e.ignoreShapes]
            if unfelt:
                raise setupcheck.SetupError(setupcheck.unfeltMessage(unfelt))

    def afterStep(self, O):
        e = self.engine
        if e._ids:
            yadeglue.applyReactions(O, e._ids, e.world.core.obstacleReactions())


class _Spheres:
    """The coupling with YADE's spheres and clumps (spheres.py), when the engine
    couples them and a piece is there; else the core is told of no sphere.
    Its wall time goes to sphereCouplingTime()."""

    def __init__(self, engine):
        self.engine = engine
        self.coupling = None  # the SphereCoupling of this step, if any

    def beforeStep(self, O):
        e = self.engine
        core = e.world.core
        self.coupling = e._spheres if e.spheres and core.nPieces else None
        c = self.coupling
        if c is None:
            if core.nSpheres:
                core.setSpheres(*_NO_SPHERES)
            return
        t0 = time.perf_counter()
        c.margin = float(e.sphereMargin)
        # spheres edited by the script: every sphere at the start of a run and every checkPeriod
        # steps, their materials' values every step
        fullCheck = e._runStart is not None and (e._runStart[0] == O.iter or (
            e.checkPeriod and O.iter % e.checkPeriod == 0))
        c.checkChanged(O, fullCheck)
        c.beforeStep(O)
        c.seconds += time.perf_counter() - t0

    def afterStep(self, O):
        c = self.coupling
        if c is not None:
            t0 = time.perf_counter()
            c.afterStep(O)
            c.seconds += time.perf_counter() - t0 + self.engine.world.core.sphereSeconds


class _Mpy:
    """The coupling under yade.mpy (mpy.py): obstacles and spheres gathered from
    the ranks owning them before the step, forces to the owners after it."""

    def __init__(self, engine):
        self.engine = engine

    def beforeStep(self, O):
        m = self.engine._mpy
        t0 = time.perf_counter()
        m.margin = float(self.engine.sphereMargin)
        m.beforeStep(O)
        m.seconds += time.perf_counter() - t0

    def afterStep(self, O):
        m = self.engine._mpy
        t0 = time.perf_counter()
        m.afterStep(O)
        m.seconds += time.perf_counter() - t0 + self.engine.world.core.sphereSeconds


def _duration(s):
    s = int(round(s))
    return "%dh%02dm%02ds" % (s // 3600, s // 60 % 60, s % 60) if s >= 3600 else "%dm%02ds" % (s // 60, s % 60)


def _step(qdemId):
    """Called by the PyRunner command of a QdemEngine: one QDEM step.  A QDEM
    error is kept for the wrappers of O.run/O.step/O.wait, which hand it to the
    script as itself (YADE would turn it into 'RuntimeError: PyRunner error.')."""
    engine = lifecycle.engineFor(qdemId)
    try:
        engine._run()
    except Exception as e:
        lifecycle._pending.append(e)
        # YADE's periodic engines mark a step done before their command runs
        # (iterLast = O.iter), and a step that raised does not advance O.iter:
        # a script that catches the error and runs on (doc/yade.md) would have
        # its next step skip QDEM while NewtonIntegrator still moved YADE's
        # bodies, and QDEM's clock would stay a step behind for good.
        if engine is not None:
            engine.iterLast = O.iter - 1
        raise
