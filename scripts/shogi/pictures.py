"""A picture of a shogi run at a chosen time, drawn by qdem.render (VTK) from
the VTU frames scripts/shogi/domino.py wrote: the pieces coloured by von Mises
stress, with its legend.

    /usr/bin/python3.11 scripts/shogi/pictures.py out/shogi/<run> <time [s]> <out.png> [--view follow|line]
                        [--around 2] [--moving 0.5] [--elev E] [--azim A]

--view follow (default): the camera follows the front, the pieces moving
fastest at that time and their neighbours moving at least `--moving` times as
fast (qdem.render.frontPieces),
and `--around` more on either side, seen obliquely from behind the front; the
rest of the line drawn around them.  --view line: the whole line.
The time counts from the push (hits.json: settle_s); the frame nearest to it
is drawn, and a time farther than half a frame interval from every frame is
refused with the times there are.  doc/shogi.md gives the command for each
of its pictures.
"""
import argparse
import json
import os
import re
import sys

import meshio
import numpy as np

from qdem import render


def frames(run):
    """[(time, vtu path)] of the run's .pvd collection, in time order."""
    pvd = [f for f in os.listdir(run) if f.endswith(".pvd")]
    if not pvd:
        sys.exit("pictures: no .pvd collection in %s (run scripts/shogi/domino.py first)" % run)
    text = open(os.path.join(run, pvd[0])).read()
    return sorted((float(t), os.path.join(run, f)) for t, f in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', text))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("time", type=float, help="seconds after the push")
    ap.add_argument("out")
    ap.add_argument("--view", choices=("follow", "line"), default="follow")
    ap.add_argument("--around", type=int, default=2)
    ap.add_argument("--moving", type=float, default=0.5, help="share of the fastest speed that counts as moving")
    ap.add_argument("--elev", type=float, default=None)
    ap.add_argument("--azim", type=float, default=None)
    a = ap.parse_args()
    hits = json.load(open(os.path.join(a.run, "hits.json")))
    t0 = hits.get("settle_s", 0.0)
    fr = frames(a.run)
    times = np.array([t - t0 for t, _ in fr])
    k = int(np.argmin(np.abs(times - a.time)))
    spacing = np.min(np.diff(times)) if len(times) > 1 else np.inf
    if abs(times[k] - a.time) > 0.5 * spacing + 1e-9:
        sys.exit("pictures: no frame near t = %g s in %s; frames at %s s after the push"
                 % (a.time, a.run, ", ".join("%.4g" % t for t in times)))
    t = times[k]
    m = meshio.read(fr[k][1])
    X = np.asarray(m.points, float)
    tets = m.cells_dict["tetra"]
    cell = {n: np.asarray(m.cell_data_dict[n]["tetra"]) for n in ("piece", "vonMises")}
    tetPiece = cell["piece"].ravel().astype(int)
    tris, owner = render.surfaceOfTets(tets)
    val = cell["vonMises"].ravel()[owner]
    nodePiece = np.asarray(m.point_data["piece"]).ravel().astype(int)
    nPieces = int(nodePiece.max()) + 1
    title = "%s, piece friction %g, t = %.2f s" % (hits["scene"], hits["frictionPiece"], t)
    hit = sum(1 for h in hits["firstHit_s"] if h is not None and h <= t + 1e-9)
    if a.view == "follow":
        ref = X - np.asarray(m.point_data["displacement"])
        speed = np.sqrt((np.asarray(m.point_data["velocity"]) ** 2).sum(axis=1))
        centres = [ref[nodePiece == p].mean(axis=0) for p in range(nPieces)]
        speeds = [speed[nodePiece == p].max() for p in range(nPieces)]
        focus = render.frontPieces(centres, speeds, around=a.around, moving=a.moving)
        frame = np.flatnonzero(np.isin(nodePiece, focus))
        shown = np.isin(tetPiece[owner], focus)
        vmax = float(np.percentile(val[shown], 99.5))  # contact spots would wash out the rest
        title += ": pieces %d-%d (%d of %d hit so far)" % (min(focus) + 1, max(focus) + 1, hit, nPieces)
        render.surfacePlot(X, tris, val, a.out, title, elev=22 if a.elev is None else a.elev,
                           azim=-60 if a.azim is None else a.azim, vmax=vmax, floor=0.0, frame=frame)
    else:
        title += " (%d of %d hit so far)" % (hit, nPieces)
        render.surfacePlot(X, tris, val, a.out, title, elev=18 if a.elev is None else a.elev,
                           azim=-120 if a.azim is None else a.azim, vmax=float(np.percentile(val, 99.5)), floor=0.0,
                           size=(1600, 500))  # the line seen from low down: a wide picture
    print("pictures: %s, frame %s (t = %.4g s after the push) -> %s" % (a.view, fr[k][1], t, a.out))


if __name__ == "__main__":
    main()
