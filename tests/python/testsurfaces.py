"""Closed triangle surfaces generated for the meshSurface tests and bench: the
kinds users bring (a scan, a figurine with thin ears, a CAD-like chess knight),
made here rather than downloaded.

Scan-like surfaces are isosurfaces of a signed distance (negative inside)
extracted by marching tetrahedra on a regular grid, as surface
reconstructions of scans are: many small triangles, some of them needles and
caps, whose normals scatter far more than the surface's curvature.
"""
import numpy as np

# Six tetrahedra per grid cube (Kuhn subdivision along the diagonal 0-7, corner
# bits x=1, y=2, z=4): the same split in every cube gives a conforming grid.
_KUHN = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]])


def _caseTable():
    """For each of the 16 inside/outside patterns of a tet's corners, its
    triangles as triples of local edges (corner pairs)."""
    table = []
    for p in range(16):
        inside = [i for i in range(4) if p >> i & 1]
        outside = [i for i in range(4) if not p >> i & 1]
        if len(inside) in (1, 3):
            a = inside[0] if len(inside) == 1 else outside[0]
            rest = outside if len(inside) == 1 else inside
            table.append([[(a, rest[0]), (a, rest[1]), (a, rest[2])]])
        elif len(inside) == 2:
            (a, b), (c, d) = inside, outside
            table.append([[(a, c), (a, d), (b, d)], [(a, c), (b, d), (b, c)]])
        else:
            table.append([])
    return table


_TABLE = _caseTable()


def isosurface(sdf, lo, hi, spacing):
    """Closed surface {sdf = 0} inside the box [lo, hi] (sdf > 0 on the box's
    boundary), by marching tetrahedra at grid `spacing`.  sdf maps (n, 3)
    points to (n,) values.  Returns (vertices (V,3), triangles (F,3) int32),
    outward oriented."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    n = np.maximum(np.ceil((hi - lo) / spacing).astype(int), 2)
    axes = [lo[k] + (hi[k] - lo[k]) * np.arange(n[k] + 1) / n[k] for k in range(3)]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    pts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    f = np.asarray(sdf(pts), dtype=float)
    h = min((hi - lo) / n)
    # No grid value at (or within 1 % of a cell of) zero: the surface would
    # pass through a grid node and give degenerate triangles.
    small = np.abs(f) < 0.01 * h
    f[small] = np.where(f[small] < 0, -0.01 * h, 0.01 * h)
    sy, sz = n[2] + 1, (n[1] + 1) * (n[2] + 1)
    i, j, k = np.meshgrid(np.arange(n[0]), np.arange(n[1]), np.arange(n[2]), indexing="ij")
    base = (i * sz + j * sy + k).ravel()
    corner = np.array([(c & 1) * sz + (c >> 1 & 1) * sy + (c >> 2 & 1) for c in range(8)])
    cubes = base[:, None] + corner[None, :]                     # (C, 8) node ids
    tets = cubes[:, _KUHN].reshape(-1, 4)                        # (6C, 4)
    inside = f[tets] < 0
    pattern = (inside * (1 << np.arange(4))).sum(1)
    keep = (pattern > 0) & (pattern < 15)
    tets, pattern = tets[keep], pattern[keep]
    edges, owner = [], []
    for p in range(1, 15):
        sel = np.nonzero(pattern == p)[0]
        for tri in _TABLE[p]:
            e = np.stack([np.stack([tets[sel, a], tets[sel, b]], 1) for a, b in tri], 1)   # (m, 3, 2)
            edges.append(e)
            owner.append(sel)
    edges = np.concatenate(edges)
    owner = np.concatenate(owner)
    edges.sort(axis=2)
    keys = edges[..., 0].astype(np.int64) * len(f) + edges[..., 1]
    uniq, tris = np.unique(keys.ravel(), return_inverse=True)
    tris = tris.reshape(-1, 3).astype(np.int32)
    a, b = uniq // len(f), uniq % len(f)
    t = f[a] / (f[a] - f[b])
    verts = pts[a] + t[:, None] * (pts[b] - pts[a])
    # Outward: the normal points from the tet's inside corners to its outside ones.
    tt = tets[owner]
    ins = inside[keep][owner]
    cin = (pts[tt] * ins[..., None]).sum(1) / ins.sum(1)[:, None]
    cout = (pts[tt] * ~ins[..., None]).sum(1) / (~ins).sum(1)[:, None]
    v = verts[tris]
    nrm = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    flip = np.einsum("ij,ij->i", nrm, cout - cin) < 0
    tris[flip] = tris[flip][:, ::-1]
    return verts, tris


def _ellipsoid(p, c, r):
    """Approximate signed distance to an ellipsoid (centre c, semi-axes r)."""
    q = (p - c) / r
    return (np.linalg.norm(q, axis=1) - 1.0) * min(r)


def _smoothUnion(a, b, k):
    """Union of two signed distances, filleted over a width k."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b * (1 - h) + a * h - k * h * (1 - h)


def bumpyBall(radius=0.5, bumps=0.04, spacing=None, seed=1):
    """A ball with noisy radial bumps (a scan of a rough stone): relative
    amplitude `bumps`, about 40 random bumps on the scale of radius/3."""
    rng = np.random.default_rng(seed)
    dirs = rng.normal(size=(40, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    amp = rng.uniform(-1, 1, 40) * bumps * radius

    def sdf(p):
        r = np.linalg.norm(p, axis=1)
        u = p / np.maximum(r, 1e-12)[:, None]
        bump = (amp[None, :] * np.exp(-(1 - u @ dirs.T) / 0.06)).sum(1)
        return r - radius * (1 + 0) - bump

    ext = radius * (1 + 3 * bumps) + 0.05 * radius
    return isosurface(sdf, [-ext] * 3, [ext] * 3, spacing or radius / 24)


def bunny(size=1.0, ears=0.06, spacing=None):
    """A bunny-like scan: body, head and two ears (ellipsoids, filleted
    unions), height about `size`; the ears are `ears` x size thick."""
    s = size
    e = max(0.5 * ears, 0.02)
    parts = [((0.0, 0.0, 0.28), (0.42, 0.30, 0.28)),        # body
             ((0.30, 0.0, 0.52), (0.18, 0.15, 0.16)),       # head
             ((0.26, -0.04 - e, 0.80), (0.07, e, 0.22)),    # ears
             ((0.26, 0.04 + e, 0.80), (0.07, e, 0.22))]

    def sdf(p):
        q = p / s
        d = _ellipsoid(q, np.array(parts[0][0]), np.array(parts[0][1]))
        for c, r in parts[1:]:
            d = _smoothUnion(d, _ellipsoid(q, np.array(c), np.array(r)), 0.04)
        return d * s

    return isosurface(sdf, np.array([-0.5, -0.45, -0.05]) * s, np.array([0.5, 0.45, 1.08]) * s, spacing or s / 70)


def bodyWithPlate(thickness=0.04, spacing=None):
    """A 0.4 m ball with a thin plate (an ear or a fin) 0.5 m x 0.3 m x
    `thickness` standing out of it: a figurine part thinner than the cells a
    user asks for the body."""
    t = thickness

    def sdf(p):
        ball = np.linalg.norm(p, axis=1) - 0.2
        q = np.abs(p - np.array([0.0, 0.0, 0.3])) - np.array([0.25, t / 2, 0.15])
        plate = np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(1), 0)
        return _smoothUnion(ball, plate, 0.02)

    return isosurface(sdf, [-0.3, -0.25, -0.25], [0.3, 0.25, 0.5], spacing or t / 3)


def polygonPrism(outline, z0, z1):
    """Closed surface of a prism over a simple polygon (counter-clockwise
    (n,2) outline) from z0 to z1, the caps triangulated by ear clipping."""
    p = np.asarray(outline, float)
    n = len(p)
    idx = list(range(n))
    caps = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    while len(idx) > 3:
        for m in range(len(idx)):
            a, b, c = idx[m - 1], idx[m], idx[(m + 1) % len(idx)]
            if cross(p[a], p[b], p[c]) <= 0:
                continue
            if any(cross(p[a], p[b], p[q]) >= 0 and cross(p[b], p[c], p[q]) >= 0 and cross(p[c], p[a], p[q]) >= 0
                   for q in idx if q not in (a, b, c)):
                continue
            caps.append((a, b, c))
            idx.pop(m)
            break
        else:
            raise ValueError("polygonPrism: the outline is not a simple counter-clockwise polygon")
    caps.append(tuple(idx))
    verts = np.vstack([np.column_stack([p, np.full(n, z1)]), np.column_stack([p, np.full(n, z0)])])
    tris = [t for t in caps] + [(n + c, n + b, n + a) for a, b, c in caps]
    for i in range(n):
        j = (i + 1) % n
        tris += [(i, n + i, n + j), (i, n + j, j)]
    return verts, np.array(tris, dtype=np.int32)


# A chess knight's side outline (x forward, y up), metres, base to the top of
# the mane: a CAD part, all flat faces and sharp edges.
KNIGHT = [(-0.020, 0.000), (0.020, 0.000), (0.020, 0.006), (0.012, 0.010), (0.010, 0.022), (0.016, 0.030),
          (0.024, 0.036), (0.026, 0.042), (0.020, 0.046), (0.010, 0.044), (0.004, 0.050), (-0.002, 0.054),
          (-0.010, 0.050), (-0.014, 0.040), (-0.012, 0.024), (-0.014, 0.010), (-0.020, 0.006)]


def knight(thickness=0.016):
    """A chess-knight-like part: the KNIGHT outline extruded `thickness`."""
    return polygonPrism(KNIGHT, -thickness / 2, thickness / 2)


def volume(surface):
    """Volume enclosed by a closed, outward-oriented triangle surface."""
    v, t = surface
    v = np.asarray(v, float) - np.asarray(v, float).mean(0)
    return np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6.0


def stepFactor(mesh):
    """How much the worst element cuts the elastic stable step against the
    median one: median / smallest of the tets' smallest heights (the
    elastic step of a linear tet ~ its smallest height / P-wave speed)."""
    h = minHeights(mesh)
    return float(np.median(h) / h.min())


def minHeights(mesh):
    """Smallest height of each tet: 3 V / largest face area."""
    x = mesh.nodes[mesh.tets]
    vol = np.abs(np.einsum("ij,ij->i", x[:, 1] - x[:, 0], np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]))) / 6
    faces = [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)]
    area = np.max([0.5 * np.linalg.norm(np.cross(x[:, b] - x[:, a], x[:, c] - x[:, a]), axis=1)
                   for a, b, c in faces], axis=0)
    return 3 * vol / area
