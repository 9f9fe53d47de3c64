"""Headless PNG snapshots of QDEM pieces, surfaces coloured by von Mises stress
(matplotlib, no display needed)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from .stress import vonMises  # noqa: E402


def snapshot(world, path, title="", elev=18, azim=-60, vmax=None, floor=None):
    """Write a PNG of every piece's surface; each triangle takes the von Mises
    stress of its tetrahedron.  vmax fixes the colour scale across frames."""
    core = world.core
    X = core.pos
    vm = vonMises(core.stress())
    tris, colors = [], []
    for p in range(core.nPieces):
        s = core.pieceSurface(p)
        tris.append(s["triangles"])
        colors.append(_faceStress(core, p, s, vm))
    tris = np.vstack(tris)
    val = np.concatenate(colors)
    vmax = vmax or max(float(val.max()), 1e-30)
    fig = plt.figure(figsize=(9, 5.5))
    ax = fig.add_subplot(111, projection="3d")
    poly = Poly3DCollection(X[tris], linewidths=0.05, edgecolors=(0, 0, 0, 0.15))
    poly.set_array(val)
    poly.set_cmap("jet")
    poly.set_clim(0, vmax)
    ax.add_collection3d(poly)
    lo, hi = X.min(axis=0), X.max(axis=0)
    span = (hi - lo).max()
    mid = 0.5 * (lo + hi)
    ax.set_xlim(mid[0] - span / 2, mid[0] + span / 2)
    ax.set_ylim(mid[1] - span / 2, mid[1] + span / 2)
    ax.set_zlim(max(lo[2], mid[2] - span / 2), max(lo[2], mid[2] - span / 2) + span)
    if floor is not None:
        xx, yy = np.meshgrid([mid[0] - span / 2, mid[0] + span / 2], [mid[1] - span / 2, mid[1] + span / 2])
        ax.plot_surface(xx, yy, np.full_like(xx, floor), color=(0.8, 0.8, 0.8, 0.3))
    ax.view_init(elev=elev, azim=azim)
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    fig.colorbar(poly, ax=ax, shrink=0.6, label="von Mises stress [Pa]")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return vmax


def _faceStress(core, piece, surf, vm):
    """Stress of the tetrahedron owning each surface triangle."""
    return vm[surf["triTet"]]
