"""Only the effects a scene calls for (issue 6, part 3): the cost of each effect
switched on, switched off, and present with a zero value, on the 27-cube
Figure 6 scene (165,888 tets, every face in contact), 2 threads.

    /usr/bin/python3.11 scripts/bench/bench_effects.py [--steps 20] [--out out/bench]
"""
import argparse
import json
import os
import time

import qdem
from qdem import _core

import bench_cubes27
from benchutil import msPerStep


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    _core.setThreads(2)
    base = bench_cubes27.scene()
    base.core.step(6.4e-6, 20)                      # contacts formed
    n = a.steps
    res = {}

    def switch(name, attr, onValue, offValue, zeroWorld=None):
        setattr(base.core, attr, onValue)
        on = msPerStep(base, n)
        setattr(base.core, attr, offValue)
        off = msPerStep(base, n)
        setattr(base.core, attr, onValue)
        zero = msPerStep(zeroWorld, n) if zeroWorld is not None else off
        res[name] = {"on_ms": on, "off_ms": off, "zero_valued_ms": zero}
        print("effect %-12s on %.2f ms, off %.2f ms, zero-valued %.2f ms" % (name, on, off, zero), flush=True)

    noVisc = bench_cubes27.scene(mat=qdem.QdemMat(viscosity=0.0))
    noVisc.core.step(6.4e-6, 20)
    switch("viscosity", "viscosityOn", True, False, noVisc)
    noFric = bench_cubes27.scene(mat=qdem.QdemMat(frictionPiece=0.0, frictionWall=0.0))
    noFric.core.step(6.4e-6, 20)
    switch("friction", "frictionOn", True, False, noFric)
    noEdges = bench_cubes27.scene()
    noEdges.core.edgeFeatureAngle = 3.2                 # no edge is a feature edge: nothing to test
    noEdges.core.step(6.4e-6, 20)
    switch("edgeEdge", "edgeEdgeOn", True, False, noEdges)
    switch("pointPolygon", "pointPolygonOn", True, False)
    switch("energy", "trackEnergy", True, False)
    flat = bench_cubes27.scene()
    flat.core.gravity = (0, 0, 0)
    flat.core.step(6.4e-6, 20)
    switch("gravity", "gravity", (0, 0, -9.80665), (0, 0, 0), flat)
    t = time.perf_counter()
    for _ in range(5):
        base.core.stress()
    res["stressOutput"] = {"on_ms": 1e3 * (time.perf_counter() - t) / 5, "off_ms": 0.0, "zero_valued_ms": 0.0,
                           "note": "computed only when a recorder asks (per frame, not per step)"}
    print("stress output: %.2f ms per frame" % res["stressOutput"]["on_ms"])
    # Pieces out of reach: the same cubes spread 1 m apart pay no contact work.
    apart = qdem.World()
    for i in range(27):
        apart.addPiece(qdem.boxMesh((4, 4, 4), (8, 8, 8), tetsPerCell=12), qdem.QdemMat(), pos=(5.0 * i, 0, 10))
    res["contactsOutOfReach"] = {"on_ms": res["pointPolygon"]["on_ms"], "off_ms": res["pointPolygon"]["off_ms"],
                                 "zero_valued_ms": msPerStep(apart, n),
                                 "note": "zero_valued: same 27 cubes far apart (no piece can reach another)"}
    print("27 cubes apart: %.2f ms" % res["contactsOutOfReach"]["zero_valued_ms"])
    # YADE spheres (what QdemEngine hands over from the scene): 2,025 spheres
    # resting on the top of the stack, the same spheres listed but 1 m above it,
    # and none at all (a scene without spheres: the phase returns at once).
    import numpy as np
    top = base.core.pos[:, 2].max()
    R = 0.05
    g = np.linspace(-5.5, 5.5, 45)
    xy = np.array([(x, y) for x in g for y in g])
    k = len(xy)
    npc = base.core.nPieces
    props = [np.full(k, v) for v in (R, 1e8, 0.3, 0.5, -1.0, 1.0)]
    pairs = (np.arange(0, k * npc + 1, npc, dtype=np.int32), np.tile(np.arange(npc, dtype=np.int32), k))

    def spheresAt(z):
        base.core.setSpheres(np.arange(k, dtype=np.int32), *props, *pairs)
        pos = np.column_stack([xy, np.full(k, z)])
        base.core.setSphereStates(pos, np.zeros((k, 3)), np.zeros((k, 3)))
        return msPerStep(base, n)

    on = spheresAt(top + 0.04 + R - 0.002)
    zero = spheresAt(top + 1.0)
    base.core.setSpheres(np.zeros(0, np.int32), *[np.zeros(0)] * 6, np.zeros(1, np.int32), np.zeros(0, np.int32))
    off = msPerStep(base, n)
    res["yadeSpheres"] = {"on_ms": on, "off_ms": off, "zero_valued_ms": zero,
                          "note": "2,025 spheres on the stack's top / none / listed but 1 m above it"}
    print("effect yadeSpheres   on %.2f ms, off %.2f ms, zero-valued %.2f ms" % (on, off, zero), flush=True)
    json.dump({"tets": base.core.nTets, "threads": 2, "steps": n, "effects": res},
              open(os.path.join(a.out, "effects.json"), "w"), indent=2)


if __name__ == "__main__":
    main()
