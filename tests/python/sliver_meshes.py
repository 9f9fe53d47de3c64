"""Sliver-laden tetrahedral meshes as users bring them: a closed surface
written here, filled by Debian's TetGen without its quality option
(``tetgen -p``: only the surface's vertices, no Steiner points), which leaves
slivers.  Used by tests/python/test_improve_mesh.py and
scripts/doc/improve_mesh_figures.py."""
import os
import shutil
import subprocess

import numpy as np

import qdem


def haveTetgen():
    return shutil.which("tetgen") is not None


def _grid(n0, n1):
    """Triangles of an (n0+1) x (n1+1) grid of vertices numbered row by row."""
    tris = []
    for i in range(n0):
        for j in range(n1):
            a, b, c, d = i * (n1 + 1) + j, i * (n1 + 1) + j + 1, (i + 1) * (n1 + 1) + j + 1, (i + 1) * (n1 + 1) + j
            tris += [(a, b, c), (a, c, d)]
    return tris


def boxSurface(size=(0.2, 0.1, 0.1), h=0.02, jitter=0.25, seed=1):
    """A box centred on the origin, each face a grid of cells about h whose
    vertices are moved at random by up to ``jitter`` cells within the face
    (along the edge for an edge's vertices; corners stay): flat faces, sharp
    edges, and the irregular triangles that make TetGen leave slivers."""
    size = np.asarray(size, float)
    rng = np.random.default_rng(seed)
    n = np.maximum(1, np.round(size / h).astype(int))
    verts, tris, index = [], [], {}

    def vid(ijk):
        if ijk not in index:
            index[ijk] = len(verts)
            free = np.array([0 < ijk[a] < n[a] for a in range(3)])
            shift = np.where(free, rng.uniform(-jitter, jitter, 3), 0.0)
            verts.append(((np.asarray(ijk) + shift) / n - 0.5) * size)
        return index[ijk]

    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        for side in (0, n[axis]):
            ids = np.empty((n[u] + 1, n[v] + 1), dtype=int)
            for i in range(n[u] + 1):
                for j in range(n[v] + 1):
                    ijk = [0, 0, 0]
                    ijk[axis], ijk[u], ijk[v] = side, i, j
                    ids[i, j] = vid(tuple(ijk))
            for (a, b, c) in _grid(n[u], n[v]):
                ia, ib, ic = (divmod(x, n[v] + 1) for x in (a, b, c))
                tris.append((ids[ia], ids[ib], ids[ic]))
    return np.array(verts), np.array(tris)


def cylinderSurface(radius=0.05, height=0.1, segments=32, h=None):
    """A cylinder along z centred on the origin: sharp rims, side in rings,
    caps in concentric rings (no fan to a centre: no needle triangles)."""
    h = h or 2 * np.pi * radius / segments
    rings = max(1, int(round(height / h)))
    verts, tris = [], []
    ang = 2 * np.pi * np.arange(segments) / segments
    side = []
    for k in range(rings + 1):
        z = -height / 2 + height * k / rings
        side.append([len(verts) + i for i in range(segments)])
        verts += [(radius * np.cos(a), radius * np.sin(a), z) for a in ang]
    for k in range(rings):
        for i in range(segments):
            a, b = side[k][i], side[k][(i + 1) % segments]
            c, d = side[k + 1][(i + 1) % segments], side[k + 1][i]
            tris += [(a, b, c), (a, c, d)]
    nCap = max(1, int(round(radius / h)))
    for top, rim in ((False, side[0]), (True, side[-1])):
        z = height / 2 if top else -height / 2
        ringIds = [rim]
        for k in range(nCap - 1, 0, -1):
            m = max(3, int(round(segments * k / nCap)))
            r = radius * k / nCap
            ringIds.append([len(verts) + i for i in range(m)])
            verts += [(r * np.cos(2 * np.pi * (i + 0.5 * (nCap - k)) / m), r * np.sin(2 * np.pi * (i + 0.5 * (nCap - k)) / m), z)
                      for i in range(m)]
        centre = len(verts)
        verts.append((0.0, 0.0, z))
        capTris = []
        for outer, inner in zip(ringIds[:-1], ringIds[1:]):
            capTris += _stitch(verts, outer, inner)
        last = ringIds[-1]
        capTris += [(last[i], last[(i + 1) % len(last)], centre) for i in range(len(last))]
        # outward: +z on top (counter-clockwise seen from above), -z below
        for t in capTris:
            tris.append(t if top else (t[0], t[2], t[1]))
    return np.array(verts), np.array(tris)


def _stitch(verts, outer, inner):
    """Triangles (counter-clockwise seen from +z) between two concentric rings."""
    V = np.asarray(verts)
    ao = np.arctan2(V[outer, 1], V[outer, 0]) % (2 * np.pi)
    ai = np.arctan2(V[inner, 1], V[inner, 0]) % (2 * np.pi)
    i0 = int(np.argmin(ai))
    o0 = int(np.argmin(np.abs(((ao - ai[i0] + np.pi) % (2 * np.pi)) - np.pi)))
    no, ni = len(outer), len(inner)
    tris, i, o = [], 0, 0
    while i < ni or o < no:
        oa, ob = outer[(o0 + o) % no], outer[(o0 + o + 1) % no]
        ia, ib = inner[(i0 + i) % ni], inner[(i0 + i + 1) % ni]
        # advance on the ring whose next vertex comes first in angle
        nextO = (ao[(o0 + o + 1) % no] - ai[i0]) % (2 * np.pi) or 2 * np.pi
        nextI = (ai[(i0 + i + 1) % ni] - ai[i0]) % (2 * np.pi) or 2 * np.pi
        if o < no and (i >= ni or nextO <= nextI):
            tris.append((oa, ob, ia))
            o += 1
        else:
            tris.append((oa, ib, ia))
            i += 1
    return tris


def bumpyBallSurface(radius=0.05, subdivisions=3, bump=0.12):
    """An icosphere with smooth bumps: r = R (1 + bump sin 3x sin 3y sin 3z)."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        mid, nf = {}, []

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = verts[a] + verts[b]
                mid[k] = len(verts)
                verts.append(p / np.linalg.norm(p))
            return mid[k]

        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    P = np.array(verts)
    r = radius * (1 + bump * np.sin(3 * np.pi * P[:, 0]) * np.sin(3 * np.pi * P[:, 1]) * np.sin(3 * np.pi * P[:, 2]))
    return P * r[:, None], np.array(f)


def writeOff(path, verts, tris):
    with open(path, "w") as out:
        out.write("OFF\n%d %d 0\n" % (len(verts), len(tris)))
        for p in verts:
            out.write("%.17g %.17g %.17g\n" % tuple(p))
        for t in tris:
            out.write("3 %d %d %d\n" % tuple(t))


def tetgenMesh(verts, tris, workdir, name="surface"):
    """The surface filled by ``tetgen -p`` (no quality): a qdem.Mesh."""
    off = os.path.join(str(workdir), name + ".off")
    writeOff(off, verts, tris)
    subprocess.run(["tetgen", "-pQ", off], check=True, capture_output=True, timeout=300)
    return qdem.loadMesh(os.path.join(str(workdir), name + ".1.ele"), fixOrientation=True)
