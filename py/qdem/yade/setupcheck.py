"""Set-up mistakes of a YADE scene with QDEM, caught at the first step (and
every QdemEngine.checkPeriod steps) with a message that names the fix.

Each of these runs without complaint in YADE and gives wrong physics:
- QdemEngine after NewtonIntegrator: YADE bodies move before QDEM has added
  its contact forces (a sphere falls through a block; wall reactions of
  QDEM pieces are counted in the next step's forces, ~2000x the weight);
- ForceResetter after QdemEngine: QDEM's reactions are wiped;
- the collider after QdemEngine while spheres touch pieces: the lists QDEM
  reads are a step old;
- two QdemEngines stepping one world: QDEM time runs at twice O.time;
- no NewtonIntegrator: QDEM reads gravity from it (it would silently be 0)
  and YADE bodies would not move;
- a GravityEngine (or CentralGravityEngine, AxialGravityEngine): QDEM
  pieces feel NewtonIntegrator.gravity only, and would float;
- the QdemEngine run every n-th step (iterPeriod, virtPeriod, realPeriod):
  QDEM time would fall behind O.time;
- a periodic cell (O.periodic = True): pieces and their contacts would not
  wrap across it;
- NewtonIntegrator.damping > 0 with QDEM pieces and dynamic YADE bodies:
  YADE bodies are damped and QDEM nodes are not (a warning: the momentum
  they exchange is no longer conserved);
- a time stepper (GlobalStiffnessTimeStepper, ...) between QdemEngine and
  NewtonIntegrator: it changes O.dt after QDEM stepped with the old one, and
  YADE bodies move with the new one (QDEM's clock falls behind O.time);
- a ServoPIDController before QdemEngine on a body QDEM touches: it reads
  O.forces before QDEM adds its reactions (the servo sees none and drives on);
- a RotationEngine (or HelixEngine, ..., also inside a
  CombinedKinematicEngine) turning bodies about its zeroPoint before
  QdemEngine: QDEM reads the velocities it set for the coming step, not the
  step just made, and a piece stuck on such a body slips sideways by about
  w^2 r dt per second (a warning: it converges with dt).

And one that is only slow: O.dt left at YADE's default while QDEM's stable
step is 100 or more times larger (a one-time warning naming that step)."""
import math
import warnings

from yade.wrapper import CombinedKinematicEngine, RotationEngine, ServoPIDController, TimeStepper

from ..mpi import ranks as parallel
from . import lifecycle

#: O.dt of a new YADE scene (``O.reset(); O.dt`` in YADE 2023.02a).
YADE_DEFAULT_DT = 1e-8


class SetupError(RuntimeError):
    """A scene set up in a way that would silently give wrong physics."""


def unfeltMessage(unfelt):
    """The error for bodies QDEM pieces would pass through ((id, shape) pairs)."""
    shapes = sorted({name for _, name in unfelt})
    ids = [i for i, _ in unfelt]
    listed = ", ".join(str(i) for i in ids[:8]) + (" and %d more" % (len(ids) - 8) if len(ids) > 8 else "")
    return ("QdemEngine: bod%s %s %s of shape %s, which QDEM pieces do not collide with: a piece would pass "
            "through %s without a force. Pieces collide with Wall, Box, Facet and Sphere bodies (and clumps of "
            "spheres). Build such an obstacle from facets (utils.facet, geom.facetBox, ymport.stl) or boxes; "
            "if no piece can reach these bodies, let QDEM ignore them: QdemEngine(ignoreShapes=%r)."
            % ("y" if len(ids) == 1 else "ies", listed, "is" if len(ids) == 1 else "are", " and ".join(shapes),
               "it" if len(ids) == 1 else "them", shapes))


def _kinds(O):
    return [type(e).__name__ for e in O.engines]


def checkPeriods(engine):
    """QDEM advances one O.dt each time it runs: it must run every step."""
    if engine.iterPeriod != 1 or engine.virtPeriod > 0 or engine.realPeriod > 0:
        raise SetupError("QdemEngine runs every step (iterPeriod=1): with iterPeriod=%d, virtPeriod=%g, "
                         "realPeriod=%g QDEM time would fall behind O.time. Leave them at 1, 0, 0; to do less "
                         "work, use progressPeriod, checkPeriod, or a VtkRecorder's iterPeriod."
                         % (engine.iterPeriod, engine.virtPeriod, engine.realPeriod))


def check(engine, O):
    engines = list(O.engines)
    kinds = [type(e).__name__ for e in engines]
    mine = [i for i, e in enumerate(engines) if lifecycle._idOf(e) == engine.qdemId]
    if not mine:
        return  # stepped by hand (stepOnce) or from outside O.engines: nothing to order
    i = mine[0]
    checkPeriods(engine)
    if O.periodic:
        raise SetupError("QdemEngine: the scene is periodic (O.periodic = True), and QDEM pieces and their "
                         "contacts do not wrap across a periodic cell (a piece would leave it, a sphere crossing "
                         "the boundary would pass through pieces). Use walls, boxes or facets as boundaries, "
                         "or O.periodic = False.")
    fields = [(k, n) for k, n in enumerate(kinds) if n in ("GravityEngine", "CentralGravityEngine",
                                                            "AxialGravityEngine") and not engines[k].dead]
    if fields:
        raise SetupError("%s at O.engines[%d]: QDEM pieces feel the gravity of NewtonIntegrator only, so they would "
                         "float while YADE bodies fall. Remove it and set NewtonIntegrator(gravity=...) instead "
                         "(GravityEngine is deprecated in YADE for the same setting)." % (fields[0][1], fields[0][0]))
    newton = [k for k, n in enumerate(kinds) if n == "NewtonIntegrator"]
    if not newton:
        raise SetupError("QdemEngine: no NewtonIntegrator in O.engines. QDEM reads gravity from it and YADE "
                         "bodies need it to move: add NewtonIntegrator(gravity=(0, 0, -9.81)) (or gravity=(0, 0, 0))"
                         " after QdemEngine.")
    if newton[0] < i:
        raise SetupError("QdemEngine is at O.engines[%d], after NewtonIntegrator (O.engines[%d]): YADE bodies would "
                         "move before QDEM adds its contact forces, and QDEM's reactions would act a step late. "
                         "Put QdemEngine before NewtonIntegrator: [ForceResetter(), ..., QdemEngine(), "
                         "NewtonIntegrator(...)]." % (i, newton[0]))
    resetters = [k for k, n in enumerate(kinds) if n == "ForceResetter"]
    if resetters and resetters[-1] > i:
        raise SetupError("ForceResetter is at O.engines[%d], after QdemEngine (O.engines[%d]): it would wipe the "
                         "forces QDEM writes. Put ForceResetter first." % (resetters[-1], i))
    colliders = [k for k, n in enumerate(kinds) if n == "InsertionSortCollider"]
    loops = [k for k, n in enumerate(kinds) if n == "InteractionLoop"]
    if engine.spheres and engine._spheres is not None and colliders and colliders[0] > i:
        raise SetupError("InsertionSortCollider is at O.engines[%d], after QdemEngine (O.engines[%d]): QDEM "
                         "finds the spheres near its pieces through the collider. Put QdemEngine after "
                         "InsertionSortCollider and InteractionLoop." % (colliders[0], i))
    if engine.spheres and engine._spheres is not None and loops and loops[0] > i:
        raise SetupError("InteractionLoop is at O.engines[%d], after QdemEngine (O.engines[%d]): put QdemEngine "
                         "after it so both add their forces in the same step." % (loops[0], i))
    others = [e for k, e in enumerate(engines) if k != i and not getattr(e, "dead", False)
              and type(lifecycle.qdemObject(e)).__name__ == "QdemEngine" and e.world is engine.world]
    if others and not engine.dead:
        raise SetupError("Two QdemEngines step the same QDEM world (O.engines[%d] and another): QDEM time would "
                         "run at twice O.time. Keep one QdemEngine per world (set dead=True on the other)." % i)
    _checkTimeSteppers(engines, i, newton[0])
    _checkForceReaders(O, engine, engines, i, newton[0])
    _warnTurningFirst(engine, engines, i)
    damping = float(getattr(engines[newton[0]], "damping", 0.0))
    if damping > 0 and engine.world.pieces and not engine._warnedDamping:
        proxies = set(engine.proxyIds())
        yadeBodies = any(b is not None and b.dynamic and b.id not in proxies for b in O.bodies)
        if yadeBodies and abs(damping - float(engine.damping)) > 0:
            engine._warnedDamping = True
            warnings.warn("NewtonIntegrator.damping=%g damps YADE bodies but not QDEM nodes (QdemEngine.damping="
                          "%g): momentum exchanged between spheres and pieces is not conserved and the two "
                          "settle at different rates. Set NewtonIntegrator(damping=0) for dynamics, or "
                          "QdemEngine(damping=%g) to damp both alike." % (damping, float(engine.damping), damping),
                          RuntimeWarning, stacklevel=2)


def _warnTurningFirst(engine, engines, i):
    """A kinematic engine that turns bodies about a point off their centres
    (RotationEngine and its kin with rotateAroundZero) sets their vel to the
    chord of the coming step.  Run before QdemEngine, QDEM meets nodes that
    moved on the step just made against a surface velocity a step ahead:
    off by w x (w x r) dt, a steady sideways slip (a piece stuck on a drum's
    facets drifted at 1.7 x w^2 r dt / 2, tests/python/test_rotating_bodies.py).
    After QdemEngine its vel is the step just made's: exact."""
    if engine._warnedTurning or not engine.world.pieces:
        return

    def turning(e):
        if isinstance(e, CombinedKinematicEngine):  # (YADE's RotationEngine(...) + TranslationEngine(...))
            return len(e.ids) and any(turning(m) for m in e.comb)
        return isinstance(e, RotationEngine) and e.rotateAroundZero and len(e.ids) \
            and float(e.angularVelocity) != 0.0
    for k in range(i):
        e = engines[k]
        if not e.dead and turning(e):
            engine._warnedTurning = True
            warnings.warn("%s at O.engines[%d] turns its bodies about zeroPoint before QdemEngine (O.engines[%d]) "
                          "reads them: QDEM then sees the velocities it set for the coming step, not the step just "
                          "made, and a piece in contact with those bodies slips sideways by about w^2 r dt per "
                          "second of turning (a piece on a drum drifts). Put QdemEngine before it: "
                          "[..., QdemEngine(), %s(...), NewtonIntegrator(...)]."
                          % (type(e).__name__, k, i, type(e).__name__), RuntimeWarning, stacklevel=3)
            return


def _checkTimeSteppers(engines, i, newton):
    """A time stepper between QdemEngine and NewtonIntegrator sets O.dt after
    QDEM made its step with the old one, and NewtonIntegrator moves YADE
    bodies with the new one: QDEM's clock falls behind O.time at every
    change (a piece fell 2.6 mm behind a sphere after one change,
    tests/python/test_setup_refusals.py).  YADE's own order puts it right
    before NewtonIntegrator, which is where a user inserting QdemEngine
    after InteractionLoop leaves it."""
    for k in range(i + 1, newton):
        e = engines[k]
        if isinstance(e, TimeStepper) and not e.dead and getattr(e, "active", True):
            raise SetupError("%s at O.engines[%d] sets O.dt after QdemEngine (O.engines[%d]) has stepped with the "
                             "old one, and NewtonIntegrator (O.engines[%d]) then moves YADE bodies with the new "
                             "one: QDEM's clock would fall behind O.time at every change. Put it before "
                             "QdemEngine: [ForceResetter(), ..., InteractionLoop(...), %s(...), QdemEngine(), "
                             "NewtonIntegrator(...)]." % (type(e).__name__, k, i, newton, type(e).__name__))


def _checkForceReaders(O, engine, engines, i, newton):
    """A ServoPIDController reads the force on its bodies from O.forces to
    drive them: before QdemEngine it reads them without QDEM's reactions (a
    platen servoed to 20 N on a block read 0 N and pressed on to 134 N).
    After it, YADE 2023.02a's ForceContainer must be synchronised before
    the servo reads it (else YADE stops: "ForceContainer not
    thread-synchronized"), which QdemEngine then does after adding its
    reactions (engine._syncForces)."""
    coupled = ("Wall", "Box", "Facet", "Sphere", "Clump")

    def touches(e):
        for bid in e.ids:
            b = O.bodies[bid] if 0 <= bid < len(O.bodies) else None
            if b is not None and b.shape is not None and type(b.shape).__name__ in coupled:
                return True
        return False
    engine._syncForces = False
    for k, e in enumerate(engines):
        if not isinstance(e, ServoPIDController) or e.dead:
            continue
        if k < i and engine.world.pieces and touches(e):
            raise SetupError("ServoPIDController at O.engines[%d] reads the force on its bodies before QdemEngine "
                             "(O.engines[%d]) adds its reactions: it would see none from QDEM pieces and drive its "
                             "bodies on. Put it after QdemEngine and before NewtonIntegrator: [..., QdemEngine(), "
                             "ServoPIDController(...), NewtonIntegrator(...)]." % (k, i))
        if i < k < newton:
            engine._syncForces = True


def noteDefaultDt(engine, O, dt):
    """O.dt at YADE's default 1e-8 s runs a scene whose stable step is 1e-4 s
    10^4 times slower than it could, and nothing says so: warned once per
    engine and scene when QDEM's stable step is at least 100 times larger.
    A time stepper in O.engines owns O.dt, and a smaller O.dt set on purpose
    (any other value) is the user's choice: neither is warned of."""
    if O.dynDt:  # an active TimeStepper (GlobalStiffnessTimeStepper, ...) sets O.dt
        return
    stable = float(engine.world.core.stableDt()["combined"])
    if not (stable >= 100 * dt and math.isfinite(stable)):  # (inf: no piece yet, nothing to compare)
        return
    engine._warnedDefaultDt = True
    if not parallel.isWriter():
        return
    name = "this QdemEngine" + (" (label %r)" % engine.label if engine.label else "")
    warnings.warn("QdemEngine: O.dt = %g s is YADE's default, %.3g times below QDEM's stable time step %.6g s "
                  "(QdemEngine.stableTimeStep()): the run takes that many more steps than it needs. Set "
                  "O.dt = 0.8 * qe.stableTimeStep() (qe: %s) after adding the pieces; if O.dt = %g s is meant, "
                  "ignore this note (given once)." % (dt, stable / dt, stable, name, dt),
                  RuntimeWarning, stacklevel=3)
