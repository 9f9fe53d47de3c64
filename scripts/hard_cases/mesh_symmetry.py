"""Mirror symmetry of qdem.boxMesh: lumped node masses and surface-area
weights on the bottom face (doc/dev/hard_cases_notebook.md, "Mesh symmetry").

For cells n x n x n (n = 2..9) and tetsPerCell 5, 6, 12 it prints
  - mass: the offset of the bottom face's lumped-mass centre from the face
    centre, as a fraction of the cell size h (what tilts a box dropped flat:
    the first landing's centre of pressure sits there);
  - area: the same for the surface-area weights (one third of each surface
    triangle's area to its nodes), which per-node contact stiffness follows;
  - mirror: the largest relative difference between a node's lumped mass and
    that of its mirror image about any of the three mid-planes.

Run: PYTHONPATH=build/python python3 scripts/hard_cases/mesh_symmetry.py
"""
import sys

import numpy as np

from qdem import _core


def oldBoxMesh(n, k, L=1.0):
    """The splits before issue 12 (a transcription of the old BoxMesh.cpp):
    6 = every cell cut along its 000-111 diagonal; 12 = each face's diagonal
    through its smallest node id; 5 is unchanged."""
    if k == 5:
        return _core.boxMesh(n, n, n, L, L, L, 5)
    idx = lambda i, j, l: (l * (n + 1) + j) * (n + 1) + i
    g = np.arange(n + 1) / n * L - 0.5 * L
    nodes = [(g[i], g[j], g[l]) for l in range(n + 1) for j in range(n + 1) for i in range(n + 1)]
    tets = []
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for l in range(n):
        for j in range(n):
            for i in range(n):
                v = lambda a, b, c: idx(i + a, j + b, l + c)
                if k == 6:
                    for p in perms:
                        c = [0, 0, 0]
                        t = [v(0, 0, 0)]
                        for s in p:
                            c[s] = 1
                            t.append(v(*c))
                        tets.append(t)
                else:
                    centre = len(nodes)
                    nodes.append((g[i] + 0.5 * L / n, g[j] + 0.5 * L / n, g[l] + 0.5 * L / n))
                    faces = [(v(0, 0, 0), v(0, 1, 0), v(0, 1, 1), v(0, 0, 1)),
                             (v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)),
                             (v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)),
                             (v(0, 1, 0), v(1, 1, 0), v(1, 1, 1), v(0, 1, 1)),
                             (v(0, 0, 0), v(1, 0, 0), v(1, 1, 0), v(0, 1, 0)),
                             (v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1))]
                    for q in faces:
                        r = int(np.argmin(q))
                        q = q[r:] + q[:r]
                        tets.append((q[0], q[1], q[2], centre))
                        tets.append((q[0], q[2], q[3], centre))
    return np.array(nodes, float).ravel(), np.array(tets).ravel()


def lumpedMass(nodes, tets):
    p = nodes[tets]
    vol = np.abs(np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])) / 6
    m = np.zeros(len(nodes))
    for k in range(4):
        np.add.at(m, tets[:, k], vol / 4)
    return m


def bottomTriangles(nodes, tets, zmin):
    # Faces of tets lying in the plane z = zmin (the bottom face's triangles).
    tris = []
    for t in tets:
        onb = [v for v in t if abs(nodes[v, 2] - zmin) < 1e-12]
        if len(onb) == 3:
            tris.append(onb)
    return np.array(tris)


def measure(n, k, L=1.0, old=False):
    nodes, tets = oldBoxMesh(n, k, L) if old else _core.boxMesh(n, n, n, L, L, L, k)
    nodes = np.asarray(nodes).reshape(-1, 3)
    tets = np.asarray(tets).reshape(-1, 4)
    h = L / n
    m = lumpedMass(nodes, tets)
    zmin = nodes[:, 2].min()
    bot = np.abs(nodes[:, 2] - zmin) < 1e-12
    cm = (m[bot, None] * nodes[bot, :2]).sum(0) / m[bot].sum()
    tris = bottomTriangles(nodes, tets, zmin)
    p = nodes[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    a = np.zeros(len(nodes))
    for j in range(3):
        np.add.at(a, tris[:, j], area / 3)
    ca = (a[bot, None] * nodes[bot, :2]).sum(0) / a[bot].sum()
    # Mirror images: match node coordinates after x -> -x (etc.).
    key = {tuple(np.round(x / h * 2).astype(int)): i for i, x in enumerate(nodes)}
    mirror = 0.0
    for d in range(3):
        for i, x in enumerate(nodes):
            y = x.copy()
            y[d] = -y[d]
            j = key[tuple(np.round(y / h * 2).astype(int))]
            mirror = max(mirror, abs(m[i] - m[j]) / m.mean())
    return np.linalg.norm(cm) / h, np.linalg.norm(ca) / h, mirror


def main():
    print("bottom face of an n^3 box: mass-centre offset / h, area-centre offset / h,")
    print("largest mirror mismatch of lumped node masses / mean node mass; before -> after")
    print("%3s %4s %23s %23s %17s" % ("n", "tets", "mass/h", "area/h", "mirror"))
    for n in range(2, 10):
        for k in (5, 6, 12):
            b = measure(n, k, old=True)
            a = measure(n, k)
            print("%3d %4d  %9.2e -> %9.2e  %9.2e -> %9.2e  %6.3f -> %6.3f" % (n, k, b[0], a[0], b[1], a[1], b[2], a[2]))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
