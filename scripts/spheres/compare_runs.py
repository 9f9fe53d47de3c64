"""Plots the runs of scripts/spheres/friction.table together:
    python3 scripts/spheres/compare_runs.py [out/spheres] -> out/spheres/friction_sweep.png"""
import glob
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

root = sys.argv[1] if len(sys.argv) > 1 else "out/spheres"
runs = []
for path in sorted(glob.glob(os.path.join(root, "column_mu*", "collapse.json"))):
    with open(path) as f:
        runs.append(json.load(f))
if not runs:
    sys.exit("compare_runs: no %s/column_mu*/collapse.json yet (run the batch table first)" % root)
runs.sort(key=lambda r: r["sphereFriction"])
fig, ax = plt.subplots(1, 3, figsize=(12, 3.5))
for r in runs:
    s = r["series"]
    t = np.array(s["t"]) - r["gate_time"]
    lab = "mu = %g" % r["sphereFriction"]
    ax[0].plot(t, s["runout"], label=lab)
    ax[1].plot(t, s["load"], label=lab)
    after = t >= 0
    ax[2].plot(t[after], 1e3 * np.array(s["compression"])[after], label=lab)
ax[0].set(xlabel="t after gate [s]", ylabel="front x [m]", title="runout")
ax[1].set(xlabel="t after gate [s]", ylabel="N", title="load on the block")
ax[2].set(xlabel="t after gate [s]", ylabel="mm (own weight excluded)", title="block shortening")
ax[0].legend()
fig.tight_layout()
out = os.path.join(root, "friction_sweep.png")
fig.savefig(out, dpi=100)
for r in runs:
    print("mu %-5g runout %.3f m  peak load %.3g N  peak compression %.3g mm  wall %.0f s"
          % (r["sphereFriction"], r["final_runout"], r["max_block_load"], 1e3 * r["max_compression"], r["wall_s"]))
print("wrote", out)
