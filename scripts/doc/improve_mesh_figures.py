"""The figures of doc/meshes.md, "improveMesh": what qdem.improveMesh gains
(the stable step) and costs (time, volume, surface deviation) on meshes as
users bring them, made here with Debian's TetGen without its quality switch
(``tetgen -p``, which leaves slivers).

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/doc/improve_mesh_figures.py \
        [--out bench/logs/improve_mesh_figures.json]

The step is qdem's own: World.stableDt() of one piece of the mesh (E = 1 MPa,
nu = 0.3, rho = 1000 kg/m^3, no viscosity: the elastic limit), against the
same for the mesh's median element alone (what the median element allows)."""
import argparse
import json
import os
import platform
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))

import qdem  # noqa: E402
import sliver_meshes as sm  # noqa: E402

MAT = dict(young=1e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.005)


def elasticDt(mesh):
    w = qdem.World()
    w.addPiece(mesh, qdem.QdemMat(**MAT))
    return w.stableDt()["elastic"]


def medianElementDt(mesh):
    he = qdem.remesh.elementSizes(mesh.nodes, mesh.tets)
    t = int(np.argsort(he)[len(he) // 2])
    return elasticDt(qdem.Mesh(mesh.nodes[mesh.tets[t]], np.array([[0, 1, 2, 3]])))


CASES = [
    ("box 0.2 x 0.1 x 0.1, irregular faces", lambda: sm.boxSurface((0.2, 0.1, 0.1), 0.02)),
    ("cylinder R 0.05 H 0.1, 32 sides", lambda: sm.cylinderSurface(0.05, 0.1, 32)),
    ("bumpy ball R 0.05 (642 vertices)", lambda: sm.bumpyBallSurface(0.05, 3, 0.06)),
    ("bumpy ball R 0.05 (2562 vertices)", lambda: sm.bumpyBallSurface(0.05, 4, 0.06)),
    ("cylinder R 0.05 H 0.1, 64 sides", lambda: sm.cylinderSurface(0.05, 0.1, 64)),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "logs", "improve_mesh_figures.json"))
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for k, (name, surface) in enumerate(CASES):
            before = sm.tetgenMesh(*surface(), d, "case%d" % k)
            t0 = time.perf_counter()
            after = qdem.improveMesh(before)
            seconds = time.perf_counter() - t0
            rep = after.improveReport
            dtBefore, dtAfter, dtMedian = elasticDt(before), elasticDt(after), medianElementDt(after)
            row = {"case": name, "tetsBefore": before.nTets, "tetsAfter": after.nTets, "seconds": seconds,
                   "cellSize": rep["cellSize"], "stepFactorBefore": rep["before"]["stepFactor"],
                   "stepFactorAfter": rep["after"]["stepFactor"],
                   "worstHeightRatioBefore": rep["before"]["worstHeightRatio"],
                   "worstHeightRatioAfter": rep["after"]["worstHeightRatio"],
                   "dtBefore": dtBefore, "dtAfter": dtAfter, "dtMedianElement": dtMedian,
                   "stepGain": dtAfter / dtBefore, "medianOverStepAfter": dtMedian / dtAfter,
                   "volumeChange": rep["volumeChange"], "maxDeviation": rep["maxDeviation"],
                   "deviationPerCell": rep["deviationPerCell"], "featureEdges": rep["featureEdges"],
                   "corners": rep["corners"]}
            rows.append(row)
            print("%-38s %5d -> %6d tets %6.1f s  step x%.1f (median/step %.1f -> %.2f)  volume %+.2f %%  "
                  "deviation %.3f h" % (name, row["tetsBefore"], row["tetsAfter"], seconds, row["stepGain"],
                                        dtMedian / dtBefore, row["medianOverStepAfter"], 100 * row["volumeChange"],
                                        row["deviationPerCell"]))
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump({"script": "scripts/doc/improve_mesh_figures.py", "machine": platform.node(),
                   "cpu": platform.processor() or platform.machine(), "threads": 1, "material": MAT,
                   "rows": rows}, f, indent=1)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
