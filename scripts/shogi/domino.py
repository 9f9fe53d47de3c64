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
#   duration      simulated seconds
#   frames        VTU frames / PNG snapshots over the run
# Writes out/shogi/<scene>_mu<friction>_<material>/: block VTU series (.pvd),
# PNG snapshots coloured by von Mises stress, hits.json (time each piece is
# first hit) and front.png (first-hit time against position).
import json
import math
import os
import time

import numpy as np
import qdem
from qdem import render, shogi
from yade import O, ForceResetter, NewtonIntegrator, PyRunner, utils
from yade.utils import readParamsFromTable

readParamsFromTable(scene="two_rooks", frictionPiece=0.1, material="soft", duration=0.4, frames=6,
                    noTableOk=True)
from yade.params import table as P  # noqa: E402

if P.material == "table1":
    mat = qdem.QdemMat(frictionPiece=P.frictionPiece)             # seed Table 1
    scale = math.ceil(shogi.stableScale(mat))                      # see doc/shogi.md
    dt = 6.4e-6
else:
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4,
                       frictionPiece=P.frictionPiece, frictionWall=0.5)
    scale, dt = 1.0, None

out = "out/shogi/%s_mu%g_%s" % (P.scene, P.frictionPiece, P.material)
os.makedirs(out, exist_ok=True)
pieces = shogi.scene(P.scene, mat, scale)
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
H = max(shogi.KINDS[k][0] for k in shogi.SCENES[P.scene]["kinds"]) * scale * 1e-3
hitSpeed = 0.02 * math.sqrt(9.81 * H)          # a piece counts as hit above this speed
hits = [0.0] + [None] * (len(pieces) - 1)
fallen = [None] * len(pieces)                   # centre of mass below 70 % of its height: tipped ~45 deg
z0 = [p.centroid()[2] for p in pieces]
frames = []


def watch():
    for i, p in enumerate(pieces):
        if hits[i] is None and np.linalg.norm(p.velocity()) > hitSpeed:
            hits[i] = O.time
        if fallen[i] is None and p.centroid()[2] < 0.7 * z0[i]:
            fallen[i] = O.time


def frame():
    k = len(frames)
    path = "%s/snap%02d.png" % (out, k)
    vmax = render.snapshot(qdem.defaultWorld(), path, title="%s, mu=%g, t=%.3f s" % (P.scene, P.frictionPiece,
                                                                                       O.time), floor=0.0)
    frames.append((O.time, path, vmax))


engine = qdem.QdemEngine(progressPeriod=20000)
O.engines = [ForceResetter(), engine, PyRunner(command="watch()", iterPeriod=50),
             qdem.VtkRecorder(fileBase=out + "/shogi-", iterPeriod=1), NewtonIntegrator(gravity=(0, 0, -9.80665))]
limit = engine.stableDt()
O.dt = dt if dt else 0.8 * limit["combined"]
nSteps = int(P.duration / O.dt)
O.engines[3].iterPeriod = max(1, nSteps // P.frames)
O.engines[3].dead = False
print("shogi: %s, %d pieces, %d tets, scale %g, dt %.3g s (stable %.3g, %s), %d steps"
      % (P.scene, len(pieces), qdem.defaultWorld().core.nTets, scale, O.dt, limit["combined"], limit["limitedBy"],
         nSteps))
start = time.time()


def results():
    """Everything measured so far (written after every frame: a long run that
    is stopped early keeps what it found)."""
    wall = time.time() - start
    result = {"scene": P.scene, "frictionPiece": P.frictionPiece, "material": P.material, "scale": scale,
              "dt": O.dt, "pieces": len(pieces), "tets": qdem.defaultWorld().core.nTets, "simulated_s": O.time,
              "wall_s": wall, "wall_s_per_simulated_s": wall / O.time, "firstHit_s": hits, "fallen_s": fallen,
              "x0_m": [float(p.refPos[:, 0].mean()) for p in pieces]}
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


for k in range(P.frames):
    O.run(nSteps // P.frames, True)
    frame()
    results()
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
      % (O.time, wall, wall / O.time, hits, fallen, out))
