"""Close-up PNGs of a shogi run around its propagation front, rendered from
the VTU frames that scripts/shogi/domino.py wrote (so they can be made for any
frame afterwards, also of a run still going).  The front at a frame is the
last piece first hit by then (hits.json); the close-up shows the pieces from
`behind` before it to `ahead` after it, coloured by von Mises stress.

    /usr/bin/python3.11 scripts/shogi/closeups.py out/shogi/<run> [--frames all|last|i,j] [--behind 3] [--ahead 2]
"""
import argparse
import glob
import json
import os
import re
import sys

import meshio
import numpy as np

from qdem import render


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--frames", default="last")
    ap.add_argument("--behind", type=int, default=3)
    ap.add_argument("--ahead", type=int, default=2)
    a = ap.parse_args()
    vtus = sorted(glob.glob(os.path.join(a.run, "shogi-*.vtu")), key=lambda p: int(re.findall(r"(\d+)\.vtu$", p)[0]))
    if not vtus:
        sys.exit("closeups: no shogi-*.vtu frames in %s" % a.run)
    hits = json.load(open(os.path.join(a.run, "hits.json")))
    dt, t0 = hits["dt"], hits.get("settle_s", 0.0)
    pick = range(len(vtus)) if a.frames == "all" else [len(vtus) - 1] if a.frames == "last" else \
        [int(i) for i in a.frames.split(",")]
    for k in pick:
        path = vtus[k]
        it = int(re.findall(r"(\d+)\.vtu$", path)[0])
        t = it * dt - t0                                  # time since the push
        hit = [i for i, h in enumerate(hits["firstHit_s"]) if h is not None and h <= t]
        front = max(hit) if hit else 0
        lo, hi = max(0, front - a.behind), min(hits["pieces"] - 1, front + a.ahead)
        m = meshio.read(path)
        tets = m.cells_dict["tetra"]
        piece = np.asarray(m.cell_data_dict["piece"]["tetra"]).ravel()
        vm = np.asarray(m.cell_data_dict["vonMises"]["tetra"]).ravel()
        sel = (piece >= lo) & (piece <= hi)
        tris, owner = render.surfaceOfTets(tets[sel])
        out = os.path.join(a.run, "close_%05.2fs.png" % t)
        val = vm[sel][owner]
        render.surfacePlot(m.points, tris, val, out, elev=12, azim=-75, fit=True, floor=0.0,
                           vmax=float(np.percentile(val, 99.5)),  # contact spots would wash out the rest
                           title="t = %.2f s, pieces %d-%d (front: piece %d)" % (t, lo + 1, hi + 1, front + 1))
        print("closeups: wrote", out)


if __name__ == "__main__":
    main()
