"""The eight kinds of shogi piece: sizes, mesh counts, and a picture.

    /usr/bin/python3.11 scripts/shogi/pieces.py      -> out/shogi/pieces.png, out/shogi/pieces.json
"""
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from qdem.scenes import shogi  # noqa: E402

os.makedirs("out/shogi", exist_ok=True)
fig = plt.figure(figsize=(14, 3.2))
rows = {}
for i, kind in enumerate(shogi.ORDER):
    m = shogi.mesh(kind)
    s = m.surface()
    h, w, t = shogi.KINDS[kind]
    rows[kind] = {"height_mm": h, "width_mm": w, "thickness_mm": t, "nodes": m.nNodes, "tets": m.nTets,
                  "surface_nodes": len(s["nodes"]), "volume_m3": float(m.volumes().sum())}
    ax = fig.add_subplot(1, 8, i + 1, projection="3d")
    X = m.nodes[:, [0, 2, 1]] * 1000          # height (y) drawn upwards
    ax.add_collection3d(Poly3DCollection(X[s["triangles"]], facecolor=(0.93, 0.8, 0.55), edgecolor=(0, 0, 0, 0.3),
                                         linewidths=0.2))
    ax.set_xlim(-16, 16), ax.set_ylim(-16, 16), ax.set_zlim(0, 32)
    ax.view_init(elev=20, azim=-70)
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    ax.set_title("%s\n%d nodes, %d tets" % (kind, m.nNodes, m.nTets), fontsize=8)
fig.tight_layout()
fig.savefig("out/shogi/pieces.png", dpi=110)
json.dump(rows, open("out/shogi/pieces.json", "w"), indent=1)
for k, r in rows.items():
    print("%-7s %5.2f x %5.2f x %5.2f mm: %d nodes (%d on the surface), %d tets"
          % (k, r["height_mm"], r["width_mm"], r["thickness_mm"], r["nodes"], r["surface_nodes"], r["tets"]))
