"""Per-phase wall time of the moving 27-cube stack at one thread count: the
median over `--steps` steps (after `--warm`) of each phase's own timing
(World.timings), one line.  Run it alternately with two builds (PYTHONPATH)
or two thread counts to see which phases scale; the machine is shared, so
print the load beside it.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 \\
        scripts/bench/contacts/phase_times.py THREADS [--cells 8] [--warm 5] [--steps 40]
"""
import argparse
import os
import statistics as st
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "arch"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("threads", type=int)
    ap.add_argument("--cells", type=int, default=8)
    ap.add_argument("--warm", type=int, default=5)
    ap.add_argument("--steps", type=int, default=40)
    a = ap.parse_args()
    from qdem import _core
    import scenes
    _core.setThreads(a.threads)
    w, dt = scenes.cubes27World(a.cells)
    core = w.core
    core.step(dt, a.warm)
    acc = {}
    for _ in range(a.steps):
        core.step(dt, 1)
        for key, v in core.timings.items():
            acc.setdefault(key, []).append(1e3 * v)
    print(a.threads, " ".join("%s %.3f" % (k, st.median(v)) for k, v in acc.items() if st.median(v) > 0.01))


if __name__ == "__main__":
    main()
