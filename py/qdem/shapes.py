"""Ready-made piece shapes beyond boxMesh: a meshed ball."""
import numpy as np

from .mesh import meshSurface


def icosphere(radius, subdivisions):
    """Closed triangulated sphere: the icosahedron, each triangle split in four
    ``subdivisions`` times, vertices pushed onto the sphere.  Returns
    (vertices (V,3), triangles (F,3)), outward-oriented."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(int(subdivisions)):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                x = v[a] + v[b]
                v.append(x / np.linalg.norm(x))
                mid[k] = len(v) - 1
            return mid[k]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return float(radius) * np.array(v), np.array(f, dtype=np.int32)


def ballMesh(radius, cellSize, seed=0):
    """Tetrahedral mesh of a ball of the given radius [m], centred on the origin,
    with CGAL Mesh_3 at element size ``cellSize`` [m] (its surface an
    icosphere fine enough for that size)."""
    if not (radius > 0 and cellSize > 0):
        raise ValueError("ballMesh: radius and cellSize must be > 0, got %r, %r" % (radius, cellSize))
    sub = 1
    while sub < 6 and 2 * np.pi * radius / (5 * 2 ** sub) > 0.5 * cellSize:
        sub += 1
    return meshSurface(icosphere(radius, sub), cellSize, seed=seed)
