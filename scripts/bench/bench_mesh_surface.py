"""qdem.meshSurface on generated surfaces: the figures doc/meshes.md gives
(worst element against the median one, volume kept, tets, time).

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/bench_mesh_surface.py [out.json]

Writes bench/logs/mesh_surface_quality.json by default."""
import json
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "python"))

import qdem  # noqa: E402
import testsurfaces as ts  # noqa: E402
from qdem.scenes import shogi  # noqa: E402
from qdem.shapes import icosphere  # noqa: E402


def cube(side):
    v = np.array([[x, y, z] for x in (0, side) for y in (0, side) for z in (0, side)], float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                  [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int32)
    return v, f


def diagonal(s):
    v = np.asarray(s[0])
    return float(np.linalg.norm(v.max(0) - v.min(0)))


CASES = [
    ("bumpy ball (scan, 66,744 triangles), diagonal/14", lambda: ts.bumpyBall(), None),
    ("bunny-like scan, ears 0.14 thick, diagonal/14", lambda: ts.bunny(ears=0.14), None),
    ("bunny-like scan, ears 0.06 thick, diagonal/14", lambda: ts.bunny(ears=0.06), None),
    ("chess knight (CAD prism), diagonal/14", lambda: ts.knight(), None),
    ("ball r 0.15 (icosphere), cellSize 0.04", lambda: icosphere(0.15, 4), 0.04),
    ("cube 0.2, cellSize 0.04", lambda: cube(0.2), 0.04),
    ("shogi gold, cellSize 2.5 mm", lambda: shogi.surface("gold"), 0.0025),
    ("ball + plate 0.04 thick, cellSize 0.1", lambda: ts.bodyWithPlate(0.04), 0.1),
]


def main(out):
    rows = []
    for name, make, h in CASES:
        s = make()
        h = h or diagonal(s) / 14
        t0 = time.perf_counter()
        m = qdem.meshSurface(s, h)
        dt = time.perf_counter() - t0
        r = m.meshReport
        rows.append({"case": name, "cellSize": h, "inputTriangles": int(len(s[1])), "tets": int(m.nTets),
                     "seconds": round(dt, 2), "stepFactor": round(ts.stepFactor(m), 2),
                     "volumeKept": round(m.volumeKept, 5), "passes": r["passes"],
                     "surfaceSize": r["surfaceSize"], "facetDistance": r["facetDistance"],
                     "thinnest": None if not np.isfinite(r["thinnest"]) else r["thinnest"],
                     "shortFeatures": r["shortFeatures"], "shortFeatureMove": r["shortFeatureMove"],
                     "load1": os.getloadavg()[0]})
        print(json.dumps(rows[-1]), flush=True)
    for kind in ("king", "pawn"):
        t0 = time.perf_counter()
        m = shogi.mesh(kind)
        rows.append({"case": "shogi.mesh(%r) (797-node search)" % kind, "tets": int(m.nTets),
                     "seconds": round(time.perf_counter() - t0, 2), "stepFactor": round(ts.stepFactor(m), 2),
                     "volumeKept": round(m.volumeKept, 5), "load1": os.getloadavg()[0]})
        print(json.dumps(rows[-1]), flush=True)
    with open(out, "w") as f:
        json.dump({"what": "qdem.meshSurface quality: stepFactor = median / smallest of the tets' smallest "
                           "heights; volumeKept = mesh volume / volume the surface encloses",
                   "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "threads": 1, "rows": rows},
                  f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else
         os.path.join(HERE, "..", "..", "bench", "logs", "mesh_surface_quality.json"))
