"""The figures of doc/parallel.md's "Equal to serial" table for QDEM's own
scenes (the rows of YADE spheres and the seed's broad phases come from
scripts/mpi/spheres_vs_serial.py), into bench/logs/mpi_equal_to_serial.json:

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/mpi/equal_to_serial.py [part ...]

Runs the checks tests/python/test_mpi.py runs (tests/mpi/check_*.py, each
printing 'RESULT {json}' on rank 0) on the same numbers of ranks, and
records max |dx| over the largest displacement against the serial run, and
the same between 1 and 2 threads serially where the check measures it.
Parts: contactFree, contacts, rebalance, restart, sleep, implicit,
implicitWarm (all by default); named parts are run into the existing record."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
from mpi_launch import env  # noqa: E402

PATH = os.path.join(ROOT, "bench", "logs", "mpi_equal_to_serial.json")


def check(P, script, *args, threads=1, **extra):
    """Rank 0's RESULT of tests/mpi/<script> on P ranks."""
    e = env()
    e.update(OMP_NUM_THREADS=str(threads), **extra)
    cmd = ["timeout", "-k", "10", "900"]
    if P > 1:
        cmd += ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(P)]
    p = subprocess.run(cmd + ["/usr/bin/python3.11", "tests/mpi/" + script] + list(args), cwd=ROOT, env=e,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
    if p.returncode != 0 or not line:
        raise SystemExit("%s on %d ranks failed:\n%s" % (script, P, p.stdout[-3000:]))
    return json.loads(line[0][7:])


def countsEqual(r, columns=3):
    return bool(np.array_equal(np.array(r["series"])[:, :columns], np.array(r["serialSeries"])[:, :columns]))


def contactFree():
    """Four pieces falling on the floor, no piece contacts (check_contact_free.py)."""
    out = {"steps": 1000}
    for P in (2, 3, 4):
        r = check(P, "check_contact_free.py")
        out["P%d" % P] = {"dxOverDisp": r["dx"] / r["maxDisplacement"]}
    return out


def contacts(rebalance=False):
    """The slab with sliding and resting cubes and crossed edges (check_contacts.py),
    optionally with a rebalance forced half-way."""
    out = {}
    extra = {"QDEM_MPI_REBALANCE": "1"} if rebalance else {}
    for P in ((2, 4) if rebalance else (2, 3, 4)):
        r = check(P, "check_contacts.py", **extra)
        out["steps"] = r["steps"]
        out["P%d" % P] = {"dxOverDisp": r["dx"] / r["maxDisplacement"],
                          "threads2": r["dxThreads"] / r["maxDisplacement"], "countsEqual": countsEqual(r),
                          "movedNodes": r["movedNodes"][0] if r["movedNodes"] else 0,
                          "rebalances": r["rebalances"]}
    return out


def restart():
    """Saved on 3 ranks, loaded on 3, continued (check_restart.py)."""
    tmp = tempfile.mkdtemp()
    r = check(3, "check_restart.py", QDEM_MPI_TMP=tmp)
    return {"P3": {"restartVsContOverDisp": r["restartVsCont"] / r["disp"],
                   "contVsSerialOverDisp": r["contVsSerial"] / r["disp"],
                   "serialRestartVsContOverDisp": r["serialRestartVsCont"] / r["disp"]}}


def sleep():
    """Sleeping pieces (check_sleep.py) on 2 and 3 ranks; one rank on 2
    threads against the serial run on 1 gives the threads' difference."""
    out = {}
    for P, threads in ((1, 2), (2, 1), (3, 1)):
        r = check(P, "check_sleep.py", threads=threads)
        s, ss = np.array(r["series"]), np.array(r["serialSeries"])
        row = {"dxOverDisp": r["dx"] / r["disp"], "asleepAlike": bool(np.array_equal(s[:, 0], ss[:, 0])),
               "asleepAtEnd": int(ss[-1, 0]), "pieces": len(r["serialAsleep"]), "steps": 100 * len(ss)}
        out["threads2" if P == 1 else "P%d" % P] = row
    return out


def implicit(warm):
    """Implicit viscosity on the four falling pieces (check_implicit_viscosity.py),
    every solve from zero or warm-started (then with a rebalance forced half-way)."""
    out = {}
    for P in (2, 3):
        r = check(P, "check_implicit_viscosity.py", *(["warm"] if warm else []))
        its = r["iterations"]
        half = r["steps"] // 2
        lim = r["limits"]
        out["steps"] = r["steps"]
        out["P%d" % P] = {
            "dxOverDisp": r["dx"] / r["maxDisplacement"], "threads2": r["dxThreads"] / r["maxDisplacement"],
            "sameIterationsEveryRank": all(i == its[0] for i in its),
            "sameIterationsAsSerial": its[0] == r["serialIterations"],
            "iterations": {"min": min(its[0]), "max": max(its[0]), "median": float(np.median(its[0])),
                           "first": its[0][0], "afterRebalance": its[0][half] if warm else None},
            "movedNodes": r["moved"][0] if r["moved"] else 0,
            "dtOverExplicitLimit": 0.5 * lim["combinedImplicit"] / lim["combinedExplicit"],
            "preconditioner": ("jacobi", "cholesky")[r["preconditioner"]]}
    return out


PARTS = {"contactFree": contactFree, "contacts": contacts, "rebalance": lambda: contacts(True),
         "restart": restart, "sleep": sleep, "implicit": lambda: implicit(False),
         "implicitWarm": lambda: implicit(True)}

if __name__ == "__main__":
    names = sys.argv[1:] or list(PARTS)
    unknown = [n for n in names if n not in PARTS]
    if unknown:
        sys.exit("equal_to_serial.py: no part %s; parts: %s" % (unknown, ", ".join(PARTS)))
    record = json.load(open(PATH)) if sys.argv[1:] and os.path.exists(PATH) else {}
    record["source"] = "scripts/mpi/equal_to_serial.py"
    for n in names:
        record[n] = PARTS[n]()
        print(n, json.dumps(record[n]), flush=True)
        with open(PATH, "w") as f:  # after each part: a long run keeps what it measured
            json.dump(record, f, indent=1)
    print("written", PATH)
