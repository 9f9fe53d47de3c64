"""The implicit viscous solve with two builds: the same run (two viscous
cubes of 6,000 tets thrown at each other, 300 steps at half the implicit
stable step) in fresh processes, old and new interleaved; prints the largest
position/velocity difference (0 when the builds agree to the bit) and the
whole-process wall times (set-up included).

    /usr/bin/python3.11 scripts/bench/arch/implicit_old_vs_new.py OLD/python NEW/python [--rounds 3] [--threads 1]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time


def scene(build, out, threads):
    sys.path.insert(0, build)
    import numpy as np
    import qdem
    qdem._core.setThreads(threads)
    w = qdem.World()
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0, viscosity=2000.0, radius=2e-3)
    a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (10, 10, 10)), mat, pos=(-0.06, 0.02, 0), vel=(0.5, 0, 0),
                   angVel=(0, 3, 5))
    b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (10, 10, 10)), mat, pos=(0.06, -0.01, 0.01), ori=((1, 2, 3), 0.5),
                   vel=(-0.5, 0, 0))
    w.core.viscousIntegration = 1  # implicit
    w.core.step(0.5 * w.stableDt()["combinedImplicit"], 300)
    np.save(out, np.vstack([a.pos, b.pos, a.vel, b.vel]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--inner", nargs=2)
    a = ap.parse_args()
    if a.inner:
        return scene(a.inner[0], a.inner[1], a.threads)
    import numpy as np
    d = tempfile.mkdtemp()
    times = {"old": [], "new": []}
    for r in range(a.rounds):
        for which in (["old", "new"] if r % 2 == 0 else ["new", "old"]):
            build = os.path.abspath(getattr(a, which))
            t0 = time.monotonic()
            subprocess.run([sys.executable, os.path.abspath(__file__), a.old, a.new, "--threads", str(a.threads),
                            "--inner", build, os.path.join(d, which + ".npy")], check=True,
                           env=dict(os.environ, OMP_WAIT_POLICY="passive"))
            times[which].append(time.monotonic() - t0)
    diff = np.abs(np.load(os.path.join(d, "old.npy")) - np.load(os.path.join(d, "new.npy"))).max()
    print("max |difference| old vs new: %g" % diff)
    for k, v in times.items():
        print("%s: wall s per run %s (min %.2f)" % (k, " ".join("%.2f" % x for x in v), min(v)))


if __name__ == "__main__":
    main()
