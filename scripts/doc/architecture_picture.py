"""Draws doc/img/architecture.png: World::step as its phases in order, the data
they share and the state each owns (doc/architecture.md).

    /usr/bin/python3.11 scripts/doc/architecture_picture.py [--out doc/img/architecture.png]

The phase list is read from pkg/world/Phases.hpp (WorldPhases::list) so the picture
follows the code; the script fails if a phase in the picture is not in it."""
import argparse
import os
import re

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyBboxPatch

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# (member in WorldPhases::list, title, what it owns, what it writes)
PHASES = [
    ("obstacle", "ObstaclePhase", "node-obstacle history\n(body id, side, spring)", "contact forces,\nobstacle reactions"),
    ("pieceContact", "PieceContactPhase", "Verlet lists, cell grids,\npoint-polygon + edge-edge\nhistory (stable ids)", "contact forces"),
    ("sphere", "SpherePhase", "triangle grids,\nsphere-triangle history", "contact forces,\nsphere force/torque"),
    ("element", "ElementPhase", "thread layout,\nper-thread force buffers", "element forces\n(buffers)"),
    ("integration", "IntegrationPhase", "per-piece speeds", "pos, vel, force,\nkinetic energy"),
    ("sleep", "SleepPhase", "awake set, sleep clocks,\nfrozen reactions", "asleep flags,\nawake lists"),
]


def phasesInCode():
    src = open(os.path.join(ROOT, "pkg", "world", "Phases.hpp")).read()
    m = re.search(r"std::array<Phase\*, \d+> list\{([^}]*)\}", src)
    return [s.strip().lstrip("&") for s in m.group(1).split(",")]


def box(ax, x, y, w, h, text, color, size=8.5, weight="normal"):
    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.02,rounding_size=0.06", fc=color, ec="#333333", lw=1))
    ax.text(x + w / 2, y + h / 2, text, ha="center", va="center", fontsize=size, weight=weight)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "doc", "img", "architecture.png"))
    a = ap.parse_args()
    code = phasesInCode()
    names = [p[0] for p in PHASES]
    if code != names:
        raise SystemExit("WorldPhases::list is %s, the picture shows %s: update PHASES" % (code, names))

    fig, ax = plt.subplots(figsize=(13.3, 6.2))
    ax.set_xlim(0, 13.3)
    ax.set_ylim(0, 6.2)
    ax.axis("off")
    ax.text(0.2, 5.95, "World::step(dt)  (pkg/world/WorldStep.cpp)", fontsize=12, weight="bold", va="top")
    box(ax, 0.2, 4.75, 1.6, 0.8, "set-up\nbounds, energy\nstates", "#eeeeee")
    w, gap, x0 = 1.65, 0.2, 2.05
    for i, (_, title, owns, writes) in enumerate(PHASES):
        x = x0 + i * (w + gap)
        box(ax, x, 4.75, w, 0.8, title, "#cfe3f7", size=8, weight="bold")
        box(ax, x, 3.45, w, 1.05, "owns:\n" + owns, "#f7f3cf", size=7.5)
        ax.annotate("", xy=(x + w / 2, 2.75), xytext=(x + w / 2, 3.4),
                    arrowprops=dict(arrowstyle="<->", color="#555555"))
        ax.text(x + w / 2, 3.05, writes, ha="center", va="center", fontsize=7)
        if i:
            ax.annotate("", xy=(x, 5.15), xytext=(x - gap, 5.15), arrowprops=dict(arrowstyle="->", lw=1.5))
    ax.annotate("", xy=(x0, 5.15), xytext=(1.8, 5.15), arrowprops=dict(arrowstyle="->", lw=1.5))
    box(ax, 2.05, 1.55, 10.95, 1.15,
        "World data (struct of arrays, pkg/world/World.hpp): nodes pos vel refPos force extForce mass blocked nodePiece | "
        "tets tetNodes tetB tetVol0 tetPiece\nsurface surfNodes surfWeight + SurfaceIndex (triangles, edges; per-piece "
        "ranges: stable ids = piece + local id) | pieces, materials, obstacles, spheres |\n"
        "contactForce (contacts -> integration) | piece boxes | energy, clock | Settings (pkg/step/Settings.hpp, one "
        "declaration each)", "#e2f2dc", size=7.5)
    box(ax, 2.05, 0.2, 5.3, 1.05, "kernels without state (pkg/contact, pkg/element):\nContactModel (mixing), ContactLaw "
        "(spring-dashpot, friction),\nPointTriangle (candidates, inside test), Geometry,\nElementKernel + laws/ "
        "(StableNeoHookean, SaintVenantKirchhoff)", "#f1e0f5", size=7.5)
    box(ax, 7.6, 0.2, 5.4, 1.05, "Checkpoint.cpp: visits the phases' declared state\n(Phase::stateColumns, "
        "save/check/loadFields)\nWorld::report(): the phases' timings and counters", "#f9e1d4", size=7.5)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    fig.savefig(a.out, dpi=110, bbox_inches="tight")
    print("wrote", a.out)


if __name__ == "__main__":
    main()
