"""Headless PNG snapshots of QDEM pieces, surfaces coloured by von Mises stress
(matplotlib, no display needed)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from .stress import vonMises  # noqa: E402


def snapshot(world, path, title="", elev=18, azim=-60, vmax=None, floor=None, pieces=None):
    """Write a PNG of every piece's surface (or only of the piece indices in
    `pieces`, framed on them: a close-up); each triangle takes the von Mises
    stress of its tetrahedron.  vmax fixes the colour scale across frames."""
    core = world.core
    X = core.pos
    vm = vonMises(core.stress())
    tris, colors = [], []
    shown = range(core.nPieces) if pieces is None else pieces
    for p in shown:
        s = core.pieceSurface(p)
        tris.append(s["triangles"])
        colors.append(_faceStress(core, p, s, vm))
    return surfacePlot(X, np.vstack(tris), np.concatenate(colors), path, title, elev, azim, vmax, floor,
                       fit=pieces is not None)


def surfaceOfTets(tets):
    """Boundary triangles of a tet mesh (faces used by one tet only) and the
    tet owning each: for meshes read back from VTU files."""
    tets = np.asarray(tets)
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    owner = np.tile(np.arange(len(tets)), 4)
    key = np.sort(faces, axis=1)
    _, idx, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    keep = idx[count == 1]
    return faces[keep], owner[keep]


def surfacePlot(X, tris, val, path, title="", elev=18, azim=-60, vmax=None, floor=None, fit=False):
    """Write a PNG of triangles `tris` over node positions X, coloured by the
    per-triangle values `val` (von Mises stress), framed on the triangles (in
    a cube, or with fit=True in a box shaped like them: close-ups)."""
    vmax = vmax or max(float(val.max()), 1e-30)
    fig = plt.figure(figsize=(9, 5.5))
    ax = fig.add_subplot(111, projection="3d")
    poly = Poly3DCollection(X[tris], linewidths=0.05, edgecolors=(0, 0, 0, 0.15))
    poly.set_array(val)
    poly.set_cmap("jet")
    poly.set_clim(0, vmax)
    ax.add_collection3d(poly)
    used = X[np.unique(tris)]
    lo, hi = used.min(axis=0), used.max(axis=0)
    span = (hi - lo).max()
    mid = 0.5 * (lo + hi)
    if fit:  # equal scales, box shaped like what is shown
        box0, box1 = lo - 0.05 * span, hi + 0.05 * span
        if floor is not None:
            box0[2] = min(box0[2], floor)
    else:
        box0 = np.array([mid[0] - span / 2, mid[1] - span / 2, max(lo[2], mid[2] - span / 2)])
        box1 = box0 + span
    ax.set_xlim(box0[0], box1[0])
    ax.set_ylim(box0[1], box1[1])
    ax.set_zlim(box0[2], box1[2])
    if floor is not None:
        xx, yy = np.meshgrid([box0[0], box1[0]], [box0[1], box1[1]])
        ax.plot_surface(xx, yy, np.full_like(xx, floor), color=(0.8, 0.8, 0.8, 0.3))
    ax.view_init(elev=elev, azim=azim)
    ax.set_box_aspect(tuple(box1 - box0))
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
