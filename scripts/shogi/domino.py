# Shogi dominoes, the seed paper's section 5 (Figures 7-10), as a YADE script.
#
#   yade -n -x scripts/shogi/domino.py                       (defaults below)
#   yade-batch scripts/shogi/friction.table scripts/shogi/domino.py
#
# Parameters (yade-batch table columns, or the defaults):
#   scene         two_rooks | king_pawns | forty
#   frictionPiece kinetic friction between pieces (seed: 0.1 and 0.5)
#   material      table1 (seed Table 1, pieces scaled until Table 1's step is
#                 stable) | soft (E 1 MPa, no viscosity, real size: minutes, not hours)
#   duration      simulated seconds after the push
#   frames        VTU frames / PNG snapshots over the run
#   count         only the first `count` pieces of the line (0 = all)
#   settle        seconds of damped settling on the floor before the push, in
#                 units of sqrt(H/g) (0 = push at once, from the stress-free shape)
#   sleep         sleeping pieces (doc/sleeping.md): QdemEngine.sleepVelocity in
#                 units of sqrt(g H) (0 = off); sleepTime is 0.1 sqrt(H/g)
#   retire        K > 0: a piece that has fallen and lies K or more pieces behind
#                 the last one hit is made non-dynamic (Piece.dynamic = False:
#                 held where it lies, awake pieces still touch it).  The pile
#                 behind the front creeps on for seconds and would otherwise keep
#                 every fallen piece awake; doc/shogi.md checks that K = 3 leaves
#                 the front as it is.  0 = never
#   scale         material table1 only: pieces `scale` times real size, the particle
#                 radius scaled alike (0 = the smallest scale at which Table 1's
#                 6.4e-6 s is stable with explicit viscosity: 766; doc/shogi.md)
#   viscous       'explicit' | 'implicit': QdemEngine.viscousIntegration.  Table 1
#                 runs at dt = 6.4e-6 s with explicit viscosity at the default
#                 scale, otherwise at dtFactor x stableDt()['combined']
#   dtFactor      the fraction of the stable step used when it is not 6.4e-6 s
#   restart       1: a state is saved with every frame (checkpoint.npz,
#                 qdem.saveState) and a run started again goes on from the last
#                 one; 0: always from the start
# Writes out/shogi/<scene>_mu<friction>_<material>/: block VTU series (.pvd),
# PNG snapshots coloured by von Mises stress (and, for long lines, close-ups with
# the camera following the front; scripts/shogi/pictures.py and closeups.py make
# pictures afterwards from the VTU frames),
# hits.json (time each piece is
# first hit) and front.png (first-hit time against position).
import json
import math
import os
import time

import numpy as np
import qdem
from qdem import render
from qdem.scenes import shogi
from yade import O, ForceResetter, FrictMat, NewtonIntegrator, PyRunner, utils
from yade.utils import readParamsFromTable

readParamsFromTable(scene="two_rooks", frictionPiece=0.1, material="soft", duration=0.4, frames=6, count=0,
                    settle=0.0, sleep=0.0, retire=0, restart=1, scale=0, viscous="explicit",
                    dtFactor=0.8, noTableOk=True)
from yade.params import table as P  # noqa: E402



def table1Scale(mat):
    """shogi.stableScale(mat) rounded up (doc/shogi.md: 766).  It meshes the
    eight kinds (minutes on a busy machine): kept in out/shogi/table1_scale.json
    for the material it was found for."""
    path, key = "out/shogi/table1_scale.json", json.dumps(mat.dict(), sort_keys=True)
    known = json.load(open(path)) if os.path.exists(path) else {}
    if key not in known:
        known[key] = math.ceil(shogi.stableScale(mat))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path + ".tmp%d" % os.getpid(), "w") as f:
            json.dump(known, f, indent=1)
        os.replace(path + ".tmp%d" % os.getpid(), path)
    return known[key]


if P.material == "table1":
    stable = table1Scale(qdem.QdemMat(frictionPiece=P.frictionPiece))  # seed Table 1; see doc/shogi.md
    scale = P.scale or stable
    # The same geometry at every scale: the particle radius (0.04 m at 766x) scaled too.
    mat = qdem.QdemMat(frictionPiece=P.frictionPiece, radius=qdem.QdemMat().radius * scale / stable)
    dt = 6.4e-6 if (scale == stable and P.viscous == "explicit") else None
else:
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4,
                       frictionPiece=P.frictionPiece, frictionWall=0.5)
    scale, dt = 1.0, None

out = "out/shogi/%s%s_mu%g_%s%s%s%s%s" % (
    P.scene, "_n%d" % P.count if P.count else "", P.frictionPiece, P.material, "_x%g" % P.scale if P.scale else "",
    "_implicit" if P.viscous == "implicit" else "", "_sleep%g" % P.sleep if P.sleep else "",
    "_retire%d" % P.retire if P.retire else "")
os.makedirs(out, exist_ok=True)
H = max(shogi.KINDS[k][0] for k in shogi.SCENES[P.scene]["kinds"]) * scale * 1e-3
push = math.sqrt(9.81 / H)                      # as shogi.scene: ~2.6x the angular velocity that just tips it
pieces = shogi.scene(P.scene, mat, scale, count=P.count or None, push=0.0 if P.settle else push)
pivot = np.array([0.0, 0.0, mat.radius])        # the first piece's base point (its mesh origin)
# The floor: YADE's default material (E = 1e7 Pa) for the soft pieces, as stiff
# as the pieces for Table 1 (its default would let 766x pieces sink).
floorMat = O.materials.append(FrictMat(young=max(1e7, mat.young), poisson=0.3, frictionAngle=0.5))
floor = O.bodies.append(utils.wall(0, axis=2, sense=1, material=floorMat))
hitSpeed = 0.02 * math.sqrt(9.81 * H)          # a piece counts as hit above this speed
hits = [0.0] + [None] * (len(pieces) - 1)
fallen = [None] * len(pieces)                   # centre of mass below 70 % of its height: tipped ~45 deg
z0 = [p.centroid[2] for p in pieces]
frames = []


tPush = None                                    # simulated time of the push (after settling)
cgIterations = [0, 0]                           # viscousIntegration='implicit': sum and count of sampled steps


def watch():
    if P.viscous == "implicit":
        cgIterations[0] += core.counts.get("viscousIterations", 0)
        cgIterations[1] += 1
    if tPush is None:
        return
    for i, p in enumerate(pieces):
        if p.asleep:                            # still, unchanged since it fell asleep
            continue
        if hits[i] is None and np.linalg.norm(p.velocity) > hitSpeed:
            hits[i] = core.time - tPush
        if fallen[i] is None and p.centroid[2] < 0.7 * z0[i]:
            fallen[i] = core.time - tPush
    if P.retire:
        front = max(i for i, h in enumerate(hits) if h is not None)
        for i in range(front - P.retire + 1):
            if fallen[i] is not None and pieces[i].dynamic:
                pieces[i].dynamic = False


def frame():
    k = len(frames)
    path = "%s/snap%02d.png" % (out, k)
    recorder.record()
    vmax = render.snapshot(qdem.defaultWorld(), path, title="%s, mu=%g, t=%.3f s" % (P.scene, P.frictionPiece,
                                                                                       core.time - tPush), floor=0.0)
    frames.append((core.time - tPush, path, vmax))
    if len(pieces) > 5:  # and the camera following the front: the pieces moving fastest, 2 more either side
        render.snapshot(qdem.defaultWorld(), "%s/close%02d.png" % (out, k), floor=0.0, focus="front", elev=22,
                        title="%s, mu=%g, t=%.3f s, the front" % (P.scene, P.frictionPiece, core.time - tPush))


core = qdem.defaultWorld().core
engine = qdem.QdemEngine(progressPeriod=20000, viscousIntegration=P.viscous,
                         sleepVelocity=P.sleep * math.sqrt(9.81 * H), sleepTime=0.1 * math.sqrt(H / 9.81))
recorder = qdem.VtkRecorder(fileBase=out + "/shogi-", dead=True)  # frames written by frame()
O.engines = [ForceResetter(), engine, PyRunner(command="watch()", iterPeriod=50), recorder,
             NewtonIntegrator(gravity=(0, 0, -9.80665))]
limit = engine.stableDt()
O.dt = dt if dt else P.dtFactor * limit["combined"]
nSteps = int(P.duration / O.dt)
print("shogi: %s, %d pieces, %d tets, scale %g, dt %.3g s (stable %.3g, %s), %d steps"
      % (P.scene, len(pieces), qdem.defaultWorld().core.nTets, scale, O.dt, limit["combined"], limit["limitedBy"],
         nSteps))
start = time.time()
wallBefore = 0.0                                # wall time of the runs this one restarts
checkpoint = out + "/checkpoint.npz"
if P.restart and os.path.exists(checkpoint):
    saved = json.loads(qdem.loadState(checkpoint)["script"])
    tPush, hits, fallen, z0 = saved["tPush"], saved["hits"], saved["fallen"], saved["z0"]
    frames[:] = [tuple(f) for f in saved["frames"]]
    recorder.frames = [tuple(f) for f in saved["vtk"]]
    wallBefore = saved["wall"]
    print("shogi: restarted from %s at t=%.4g s after the push (%d frames done)" % (checkpoint, core.time - tPush,
                                                                                    len(frames)))
elif P.settle:
    # Settle on the floor under gravity by kinetic damping (dynamic relaxation:
    # each piece's velocities are zeroed whenever its kinetic energy has just
    # peaked), then start from rest: the line stands still before the first
    # piece is tipped.
    chunk = max(1, int(0.002 * math.sqrt(H / 9.81) / O.dt))     # ~1/40 of a piece's vertical period
    lastKe = [0.0] * len(pieces)
    while core.time < P.settle * math.sqrt(H / 9.81):
        O.run(chunk, True)
        for i, p in enumerate(pieces):
            if p.asleep:
                continue
            ke = 0.5 * float((p.mass[:, None] * p._nodes("vel") ** 2).sum())
            if ke < lastKe[i]:
                p.vel[:] = 0.0
                ke = 0.0
            lastKe[i] = ke
    core.vel[:] = 0.0                           # (sleeping pieces' are zero already)
    p0 = pieces[0]
    p0.vel[:] = np.cross([0.0, push, 0.0], p0.pos - pivot)
    print("shogi: settled for %.3g s (%.0f s wall), %d pieces asleep; first piece tipped"
          % (core.time, time.time() - start, core.nAsleep))
    z0 = [p.centroid[2] for p in pieces]
if tPush is None:
    tPush = core.time


def results():
    """Everything measured so far (written after every frame: a long run that
    is stopped early keeps what it found)."""
    wall = wallBefore + time.time() - start
    result = {"scene": P.scene, "frictionPiece": P.frictionPiece, "material": P.material, "scale": scale,
              "viscous": P.viscous, "steps": O.iter,
              "cg_iterations_per_step": cgIterations[0] / max(cgIterations[1], 1),
              "dt": O.dt, "pieces": len(pieces), "tets": qdem.defaultWorld().core.nTets,
              "simulated_s": core.time - tPush, "settle_s": tPush, "sleep": P.sleep, "retire": P.retire,
              "asleep_now": qdem.defaultWorld().core.nAsleep, "wall_s": wall,
              "wall_s_per_simulated_s": wall / max(core.time, 1e-12), "firstHit_s": hits, "fallen_s": fallen,
              "x0_m": [float(p.refPos[:, 0].mean()) for p in pieces]}
    if stopped is not None:
        result["error"], result["stopped_at_step"] = stopped, O.iter
    hit = [(x, t) for x, t in zip(result["x0_m"], hits) if t is not None]
    if len(hit) >= 3:
        slope = np.polyfit([t for _, t in hit[1:]], [x for x, _ in hit[1:]], 1)[0]
        result["front_speed_m_per_s"] = float(slope)
    fell = [(x, t) for x, t in zip(result["x0_m"], fallen) if t is not None]
    if len(fell) >= 3:
        result["fall_front_speed_m_per_s"] = float(np.polyfit([t for _, t in fell], [x for x, _ in fell], 1)[0])
    with open(out + "/hits.json.tmp", "w") as f:
        json.dump(result, f, indent=1)
    os.replace(out + "/hits.json.tmp", out + "/hits.json")  # never a half-written file
    return result, hit, wall


stopped = None  # the message of a StabilityError that stopped the run (kept in hits.json as 'error')
while len(frames) < P.frames:
    tNext = tPush + (len(frames) + 1) * P.duration / P.frames
    try:
        O.run(max(1, int(round((tNext - core.time) / O.dt))), True)
    except qdem.StabilityError as e:
        stopped = str(e)
        results()
        raise
    frame()
    results()
    if P.restart:
        qdem.saveState(checkpoint, script=json.dumps({
            "tPush": tPush, "hits": hits, "fallen": fallen, "z0": z0, "frames": frames, "vtk": recorder.frames,
            "wall": wallBefore + time.time() - start}))
result, hit, wall = results()

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot([x for x, _ in hit], [t for _, t in hit], "o-", label="mu = %g" % P.frictionPiece)
ax.set_xlabel("piece position [m]")
ax.set_ylabel("first hit [s]")
ax.grid(alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(out + "/front.png", dpi=110)
print("shogi: %.3g s simulated in %.1f s (%.3g s wall per simulated s); first hits %s; fallen %s; written to %s"
      % (core.time, wall, wall / core.time, hits, fallen, out))
