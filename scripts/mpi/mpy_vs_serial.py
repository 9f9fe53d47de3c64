"""The figures of doc/parallel.md, "Under yade.mpy": tests/mpi/yade_mpy.py
(twelve spheres dropped on a block; a clump thrown along a slab) serially
with 1 and 2 QDEM threads and under yade.mpy on 3 and 4 ranks, 1,000 steps.

    /usr/bin/python3.11 scripts/mpi/mpy_vs_serial.py [out.json]

Writes bench/logs/mpi_mpy.json by default (PYTHONPATH must reach the built
qdem, as for the tests)."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(scene, P, threads=1):
    fd, out = tempfile.mkstemp(suffix=".json")
    os.close(fd)
    e = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI_", "PMIX_"))}
    e.update(OMP_NUM_THREADS=str(threads), OMP_WAIT_POLICY="passive", OMPI_MCA_mpi_yield_when_idle="1",
             QDEM_THREADS=str(threads), QDEM_MPI_OUT=out)
    cmd = ["yade", "-n", "-x", "tests/mpi/yade_mpy.py", scene]
    if P > 1:
        cmd = ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(P)] + cmd
    p = subprocess.run(["timeout", "600"] + cmd, cwd=ROOT, env=e, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
    if p.returncode:
        raise SystemExit(p.stdout[-3000:])
    with open(out) as f:
        r = json.load(f)
    os.remove(out)
    return r


def diffs(a, b):
    sa, sb = np.array(a["spheres"]), np.array(b["spheres"])
    A, B = np.array(a["series"]), np.array(b["series"])
    return {"dxOverDisp": float(np.abs(np.array(a["pos"]) - np.array(b["pos"])).max() / a["disp"]),
            "sphereStates": float(np.abs(sa - sb).max() / np.abs(sa).max()),
            "floorForce": float(np.abs(A[:, 1:4] - B[:, 1:4]).max() / np.abs(A[:, 1:4]).max()),
            "energy": float(np.abs(A[:, 4] - B[:, 4]).max() / np.abs(A[:, 4]).max()),
            "contactCountsEqual": bool(np.array_equal(A[:, 0], B[:, 0]))}


rows = {}
for scene in ("drop", "clump"):
    s1, s2 = run(scene, 1, 1), run(scene, 1, 2)
    rows[scene] = {"serial1vs2threads": diffs(s1, s2),
                   "floorForceMax": float(np.abs(np.array(s1["series"])[:, 1:4]).max())}
    for P in (3, 4):
        m = run(scene, P)
        rows[scene]["mpy%dranks" % P] = {
            "vsSerial": diffs(s1, m), "placed": m["placed"], "owners": m["owners"], "ownedNodes": m["ownedNodes"],
            "sphereContactsPerRank": m["sphereContactsPerRank"], "layerSecondsPerStep": m["layerSecondsPerStep"],
            "steps": m["iter"]}
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "bench", "logs", "mpi_mpy.json")
with open(path, "w") as f:
    json.dump(rows, f, indent=1)
print(json.dumps(rows, indent=1))
