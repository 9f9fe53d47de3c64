"""Where the moving 27-cube stack's step spends its time, by sampling: `perf
record -e cpu-clock` (a timer interrupt, so it works on this KVM guest where
`perf stat` reports no hardware counters) over --steps steps at one thread,
then the symbols' shares and, for one symbol, the instructions that the
samples land on most (a load that misses shows up as samples on the
instruction that first waits for it).

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/contacts/perf_profile.py \\
        [--steps 400] [--threads 1] [--symbol 'qdem::PieceContactPhase::pointPolygon<true>'] [--top 15] [--out FILE.txt]

Needs Debian's linux-perf.  The shares include the scene's set-up (a few
per cent: surface extraction, the first Verlet lists); with a build made
with -g (cmake -DCMAKE_CXX_FLAGS=-g) the report can also go by source line
(`perf report --sort srcline`)."""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))

SCENE = """
import sys
sys.path.insert(0, %r)
from qdem import _core
import scenes
_core.setThreads(%d)
w, dt = scenes.cubes27World(8)
w.core.step(dt, 5)
w.core.step(dt, %d)
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--symbol", default="qdem::PieceContactPhase::pointPolygon<true>")
    ap.add_argument("--top", type=int, default=15)
    ap.add_argument("--out")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="qdem_perf.")
    script = os.path.join(tmp, "scene.py")
    with open(script, "w") as f:
        f.write(SCENE % (os.path.join(HERE, "..", "..", "arch"), a.threads, a.steps))
    data = os.path.join(tmp, "perf.data")
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads), OMP_WAIT_POLICY="passive")
    subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", "5000", "-o", data, sys.executable, script],
                   env=env, check=True, stdout=subprocess.DEVNULL)
    rep = subprocess.run(["perf", "report", "-i", data, "--no-children", "--sort", "symbol", "--stdio"],
                         capture_output=True, text=True).stdout
    lines = ["# perf record -e cpu-clock, %d steps of the 27-cube stack, %d thread(s)" % (a.steps, a.threads),
             "# symbol shares:"]
    lines += [l.rstrip()[:120] for l in rep.splitlines() if "%" in l and not l.startswith("#")][:a.top]
    ann = subprocess.run(["perf", "annotate", "-i", data, "--stdio", "-s", a.symbol],
                         capture_output=True, text=True).stdout.splitlines()
    hot = []
    for i, l in enumerate(ann):
        parts = l.split(":", 1)
        try:
            pct = float(parts[0])
        except ValueError:
            continue
        if pct >= 100.0:
            continue
        hot.append((pct, i))
    hot.sort(reverse=True)
    lines.append("# %s: the instructions with most samples (%% of the symbol's), with the 3 before each:" % a.symbol)
    for pct, i in hot[:8]:
        lines.append("--")
        lines += [ann[j].rstrip()[:140] for j in range(max(0, i - 3), i + 1)]
    text = "\n".join(lines)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
