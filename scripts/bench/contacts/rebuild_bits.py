"""Bit-for-bit check of a change to the Verlet list rebuild: the moving
27-cube stack of scripts/arch/scenes.py stepped with a rebuild forced every
`--force-every` steps (verletSkin toggled to the next double above its value
and back: the lists are rebuilt whenever the skin changes), one thread, in
each build; the node positions at the end are hashed (SHA-1 of the float64
array) and compared.  compare_builds.py runs the same scene with its natural
rebuilds (a handful in 1,000 steps); this one makes every third step a
rebuild, so that the lists' content and order are exercised dozens of times.

    /usr/bin/python3.11 scripts/bench/contacts/rebuild_bits.py \
        --build OLD/python --build NEW/python [--cells 4 8] [--steps 150] \
        [--out bench/logs/rebuild_bits_2026-11-24.json]

Exits 1 when the builds' hashes differ."""
import argparse
import hashlib
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))


def inner(a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "arch"))
    import numpy as np
    from qdem import _core
    import scenes
    _core.setThreads(1)
    w, dt = scenes.cubes27World(a.cells)
    core = w.core
    skin = core.verletSkin
    r0 = core.verletRebuilds
    for k in range(a.steps):
        if k % a.force_every == a.force_every - 1:
            core.verletSkin = math.nextafter(skin, 1.0) if core.verletSkin == skin else skin
        core.step(dt, 1)
    p = np.ascontiguousarray(np.array(core.pos), dtype=np.float64)
    print(json.dumps(dict(sha1=hashlib.sha1(p.tobytes()).hexdigest(), rebuilds=int(core.verletRebuilds - r0),
                          contacts={k: int(v) for k, v in core.contactCounts.items()})))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", action="append", default=[])
    ap.add_argument("--cells", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--force-every", type=int, default=3)
    ap.add_argument("--out", default=None)
    ap.add_argument("--inner", action="store_true")
    a = ap.parse_args()
    if a.inner:
        a.cells = a.cells[0]
        return inner(a)
    rows, same = [], True
    for cells in a.cells:
        got = {}
        for b in a.build:
            env = dict(os.environ, PYTHONPATH=os.path.abspath(b), OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
            p = subprocess.run([sys.executable, os.path.abspath(__file__), "--inner", "--cells", str(cells),
                                "--steps", str(a.steps), "--force-every", str(a.force_every)],
                               env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                raise SystemExit(p.stderr[-3000:])
            got[b] = json.loads(p.stdout.strip().splitlines()[-1])
        equal = len({g["sha1"] for g in got.values()}) == 1
        same = same and equal
        rows.append(dict(cells=cells, steps=a.steps, force_every=a.force_every, equal=equal, runs=got))
        print("cells %d, %d steps, rebuilds %s: %s" % (cells, a.steps, [g["rebuilds"] for g in got.values()],
                                                      "identical" if equal else "DIFFERENT"), flush=True)
    if a.out:
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        with open(a.out, "w") as f:
            json.dump(dict(builds=a.build, rows=rows, identical=same), f, indent=1)
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
