"""Propagation fronts of the shogi dominoes at different frictions, from the
hits.json files that scripts/shogi/domino.py writes: one plot and the front
speeds (seed Figures 7 and 10: friction slows the propagation).

    /usr/bin/python3.11 scripts/shogi/compare_fronts.py [scene] [material] [--reference MATERIAL2[:label]]

With --reference, the runs of the same scene named MATERIAL2 (for instance
the same line without `retire`) are drawn as open circles in the same colour,
and the differences of first-hit times piece by piece are printed.
"""
import glob
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

args = sys.argv[1:]
reference = None
if "--reference" in args:
    i = args.index("--reference")
    if i + 1 >= len(args):
        sys.exit("--reference needs the material suffix of the reference runs")
    reference, _, refLabel = args[i + 1].partition(":")
    refLabel = refLabel or reference
    del args[i:i + 2]
scene = args[0] if len(args) > 0 else "forty"
material = args[1] if len(args) > 1 else "soft"
runs = sorted(glob.glob("out/shogi/%s_mu*_%s/hits.json" % (scene, material)))
if not runs:
    sys.exit("no runs of %s (%s) under out/shogi: run scripts/shogi/domino.py first" % (scene, material))
fig, ax = plt.subplots(figsize=(7, 4.5))
summary = {}
for path in runs:
    r = json.load(open(path))
    pts = [(x, t) for x, t in zip(r["x0_m"], r["firstHit_s"]) if t is not None]
    x, t = np.array(pts).T
    line, = ax.plot(x, t, "o-", label="first hit, friction %g" % r["frictionPiece"])
    fell = [(x_, t_) for x_, t_ in zip(r["x0_m"], r.get("fallen_s", [])) if t_ is not None]
    if fell:
        fx, ft = np.array(fell).T
        ax.plot(fx, ft, "s--", color=line.get_color(), alpha=0.7, label="fallen (45 deg), friction %g"
                % r["frictionPiece"])
    summary[r["frictionPiece"]] = {"pieces_hit": len(pts), "of": r["pieces"],
                                   "front_speed_m_per_s": r.get("front_speed_m_per_s"),
                                   "fall_front_speed_m_per_s": r.get("fall_front_speed_m_per_s"),
                                   "last_hit_s": float(t.max()),
                                   "fallen_s": r.get("fallen_s")}
    refPath = path.replace("_%s/" % material, "_%s/" % reference) if reference else None
    if refPath and glob.glob(refPath):
        ref = json.load(open(refPath))
        both = [(x_, a, b) for x_, a, b in zip(r["x0_m"], r["firstHit_s"], ref["firstHit_s"])
                if a is not None and b is not None]
        bx, _, bt = np.array(both).T
        ax.plot(bx, bt, "o", mfc="none", ms=10, color=line.get_color(),
                label="first hit, friction %g, %s" % (r["frictionPiece"], refLabel))
        summary[r["frictionPiece"]]["reference"] = {
            "material": reference, "pieces_hit": sum(t_ is not None for t_ in ref["firstHit_s"]),
            "hit_s_minus_reference_s": [round(a - b, 4) for _, a, b in both]}
ax.set_xlabel("piece position along the line [m]")
ax.set_ylabel("time of first hit [s]")
ax.set_title("%s: propagation front" % scene)
ax.grid(alpha=0.3)
ax.legend()
fig.tight_layout()
out = "out/shogi/%s_%s_fronts.png" % (scene, material)
fig.savefig(out, dpi=110)
print(json.dumps(summary, indent=1))
print("wrote", out)
