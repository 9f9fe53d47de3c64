"""The Verlet skin's trade-off on the moving 27-cube stack (scripts/arch/scenes.py):
a larger skin rebuilds the lists less often but lists more triangles per node,
which every ordinary step pays for in point-polygon.  Counted, not timed (the
counts do not depend on the machine's load): Verlet rebuilds over the run and
the listed triangles per step (contactCounts listedTriangles, mean over the
run's samples), at one thread.  testedPerStep: those passing the exact
prefilter (contactCounts listedTrianglesTested) of commit 241797d, which
doc/dev/performance_notebook.md "Contact phase" quotes; the prefilter was taken out
again after it, and later builds report 0 there.

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/contacts/skin_tradeoff.py \
        [--cells 4] [--steps 1000] [--skins 0.25 0.5 1 2] [--out bench/logs/contacts_skin_2026-11-24.json]
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "arch"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, default=4)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--chunk", type=int, default=20)
    ap.add_argument("--skins", type=float, nargs="+", default=[0.25, 0.5, 1.0, 2.0])
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    import scenes
    from qdem import _core
    _core.setThreads(1)
    rows = []
    for skin in a.skins:
        w, dt = scenes.cubes27World(a.cells)
        w.core.verletSkin = skin
        r0 = w.core.verletRebuilds
        listed, tested, contacts = [], [], []
        for _ in range(a.steps // a.chunk):
            w.core.step(dt, a.chunk)
            c = w.core.contactCounts
            listed.append(c["listedTriangles"]), tested.append(c.get("listedTrianglesTested", 0))
            contacts.append(c["pointPolygon"])
        row = dict(skin=skin, rebuilds=int(w.core.verletRebuilds - r0), steps=a.steps,
                   listedPerStep=sum(listed) / len(listed), testedPerStep=sum(tested) / len(tested),
                   contactsPerStep=sum(contacts) / len(contacts))
        rows.append(row)
        print(json.dumps(row), flush=True)
    if a.out:
        with open(a.out, "w") as f:
            json.dump(dict(scene="cubes27 moving", cells=a.cells, rows=rows), f, indent=1)


if __name__ == "__main__":
    main()
