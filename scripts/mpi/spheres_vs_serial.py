"""The figures doc/parallel.md quotes for YADE spheres and the seed's broad
phases under MPI, against serial runs, into bench/logs/mpi_spheres.json:

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/mpi/spheres_vs_serial.py

Runs tests/mpi/yade_spheres.py (scenes 'drop' and 'clump') serially with 1
and 2 QDEM threads and on P = 2, 3, 4 ranks, and tests/mpi/check_contacts.py
with broad phases A, B, C on P = 2, 3, 4; reports max |dx| over the largest
displacement, sphere states' max difference over their largest value, and
whether the contact counts equal the serial ones; and a rebalance plus
O.save / O.load on 3 ranks.  With the argument `restart` or `broad` only
that part runs, into the existing record."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
from mpi_launch import env  # noqa: E402


def launch(P, args, extra):
    e = env()
    e.update(extra)
    pre = ["timeout", "-k", "10", "600"]
    if P > 1:
        pre += ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(P)]
    return subprocess.run(pre + args, cwd=ROOT, env=e, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def spheres(scene, P, threads=1):
    fd, out = tempfile.mkstemp(suffix=".json")
    os.close(fd)
    p = launch(P, ["yade", "-n", "-x", "tests/mpi/yade_spheres.py", scene],
               {"QDEM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads), "QDEM_MPI_OUT": out})
    if p.returncode != 0:
        raise SystemExit(p.stdout[-3000:])
    with open(out) as f:
        r = json.load(f)
    os.remove(out)
    return r


def diff(a, b):
    sa, sb = np.array(a["spheres"]), np.array(b["spheres"])
    return {"dxOverDisp": float(np.abs(np.array(a["pos"]) - np.array(b["pos"])).max() / a["disp"]),
            "dSphereOverMax": float(np.abs(sa - sb).max() / np.abs(sa).max()),
            "countsEqual": bool(np.array_equal(np.array(a["series"])[:, 0], np.array(b["series"])[:, 0]))}


def broadPhases():
    """tests/mpi/check_contacts.py with the seed's broad phases A, B, C on 2-4 ranks."""
    res = {}
    for bp in ("A", "B", "C"):
        row = {}
        for P in (2, 3, 4):
            p = launch(P, ["/usr/bin/python3.11", "tests/mpi/check_contacts.py"], {"QDEM_MPI_BROADPHASE": bp})
            line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
            if p.returncode != 0 or not line:
                raise SystemExit(p.stdout[-3000:])
            r = json.loads(line[0][7:])
            s, ss = np.array(r["series"]), np.array(r["serialSeries"])
            row["P%d" % P] = {"dxOverDisp": r["dx"] / r["maxDisplacement"],
                              "threads2": r["dxThreads"] / r["maxDisplacement"],
                              "countsEqual": bool(np.array_equal(s[:, :3], ss[:, :3])),
                              "interiorFaceTestsEqual": bool(np.array_equal(s[:, 7:], ss[:, 7:])),
                              "interiorFaceTests": [int(s[:, 7:8].sum()), int(ss[:, 7:8].sum())]
                              if s.shape[1] > 7 else None}
        res[bp] = row
        print(bp, json.dumps(row), flush=True)
    return res


def restart():
    """Drop on 3 ranks, a rebalance forced and O.save at step 800, O.load, the
    last steps again: the reloaded end against the continued one."""
    tmp = tempfile.mkdtemp()
    fd, out = tempfile.mkstemp(suffix=".json")
    os.close(fd)
    p = launch(3, ["yade", "-n", "-x", "tests/mpi/yade_spheres.py", "drop"],
               {"QDEM_MPI_OUT": out, "QDEM_MPI_REBALANCE": "1", "QDEM_MPI_SAVE": os.path.join(tmp, "s.yade.gz")})
    if p.returncode != 0:
        raise SystemExit(p.stdout[-3000:])
    with open(out) as f:
        r = json.load(f)
    os.remove(out)
    rl = r["reloaded"]
    return {"movedNodes": r["movedNodes"], "rebalances": r["rebalances"], "iter": rl["iter"],
            "reloadedDxOverDisp": rl["dx"] / r["disp"],
            "reloadedDSphereOverMax": rl["dSphere"] / float(np.abs(np.array(r["spheres"])).max())}


path = os.path.join(ROOT, "bench", "logs", "mpi_spheres.json")
if sys.argv[1:] in (["restart"], ["broad"]):  # only this part, into the existing record
    with open(path) as f:
        out = json.load(f)
    if sys.argv[1] == "restart":
        out["restart"] = restart()
    else:
        out["broadPhases"] = broadPhases()
else:
    out = {"spheres": {}}
    for scene in ("drop", "clump"):
        s1, s2 = spheres(scene, 1, 1), spheres(scene, 1, 2)
        row = {"threads2": diff(s1, s2), "sphereContacts": int(np.array(s1["series"])[:, 0].sum())}
        for P in (2, 3, 4):
            r = spheres(scene, P)
            row["P%d" % P] = dict(diff(s1, r), ranksAlike=r["sphereRankSpread"] == 0.0,
                                  perRank=r["sphereContactsPerRank"])
        out["spheres"][scene] = row
        print(scene, json.dumps(row), flush=True)
    out["broadPhases"] = broadPhases()
    out["restart"] = restart()
with open(path, "w") as f:
    json.dump(out, f, indent=1)
print("written", path)
