"""How tight the point-polygon Verlet lists are on the moving 27-cube stack
(scripts/arch/scenes.py cubes27World(8), after 100 steps): per sampled
surface node (every 7th), the other pieces' surface triangles its list holds
(bounding sphere of the triangle, centroid and farthest corner, within
reach + skin: what the rebuild lists), those within reach + skin by exact
point-triangle distance, those plus the ones the node is behind by less than
the skin with its projection within the skin of the triangle (what a tighter
list would have to keep for nodes that go deep), and those within reach now.
The world's own count of listed triangles is printed for comparison.

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/contacts/list_tightness.py

doc/dev/performance_notebook.md, "Tried, not kept: point-polygon's lanes filtered".
"""
import os
import sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "arch"))
import numpy as np, scenes
from qdem import _core
_core.setThreads(1)
w, dt = scenes.cubes27World(8)
w.core.step(dt, 100)
c = w.core
X = np.array(c.pos).reshape(-1, 3)
T = np.array(c.surfaceTriangles()).reshape(-1, 3)
NP = np.array(c.nodePiece)
S = np.array(c.surfaceNodeIds)
tp = NP[T[:, 0]]
r = w.pieces[0].material.radius
reach, skin = 2 * r, c.verletSkin * r  # (verletSkin is in node radii)
A, B, C = X[T[:, 0]], X[T[:, 1]], X[T[:, 2]]
cen = (A + B + C) / 3
rad = np.max(np.stack([np.linalg.norm(A - cen, axis=1), np.linalg.norm(B - cen, axis=1), np.linalg.norm(C - cen, axis=1)]), axis=0)
nrm = np.cross(B - A, C - A); nrm /= np.linalg.norm(nrm, axis=1)[:, None]
def closest(p, a, b, c):
    # vectorised Ericson closest point on triangles for one point
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b; d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c; d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    vc = d1 * d4 - d3 * d2; vb = d5 * d2 - d1 * d6; va = d3 * d6 - d5 * d4
    with np.errstate(all='ignore'):
        den = 1 / (va + vb + vc); v = vb * den; ww = vc * den
        q = a + ab * v[:, None] + ac * ww[:, None]
        e1 = (d4 - d3) / ((d4 - d3) + (d5 - d6)); m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0); q[m] = (b + (c - b) * e1[:, None])[m]
        e2 = d2 / (d2 - d6); m = (vb <= 0) & (d2 >= 0) & (d6 <= 0); q[m] = (a + ac * e2[:, None])[m]
        m = (d6 >= 0) & (d5 <= d6); q[m] = c[m]
        e0 = d1 / (d1 - d3); m = (vc <= 0) & (d1 >= 0) & (d3 <= 0); q[m] = (a + ab * e0[:, None])[m]
        m = (d3 >= 0) & (d4 <= d3); q[m] = b[m]
        m = (d1 <= 0) & (d2 <= 0); q[m] = a[m]
    return np.linalg.norm(p - q, axis=1)
tot_bs = tot_ex = tot_exb = tot_contact = 0
for s in S[::7]:
    p = X[s]; pa = NP[s]
    o = tp != pa
    d = np.linalg.norm(cen[o] - p, axis=1)
    bs = d <= rad[o] + reach + skin
    idx = np.nonzero(o)[0][bs]
    dist = closest(p, A[idx], B[idx], C[idx])
    h = ((p - A[idx]) * nrm[idx]).sum(1)
    ex = dist <= reach + skin
    lateral = np.sqrt(np.maximum(dist * dist - h * h, 0.0))
    exb = ex | ((h < skin) & (lateral <= skin))
    tot_bs += bs.sum(); tot_ex += ex.sum(); tot_exb += exb.sum(); tot_contact += (dist < reach).sum()
print("per sampled node: bounding-sphere %.2f, exact dist %.2f, exact or behind within skin %.2f, within reach now %.2f" % (tot_bs / len(S[::7]), tot_ex / len(S[::7]), tot_exb / len(S[::7]), tot_contact / len(S[::7])))
rep = dict(c.counts)
print(rep)
print("surface nodes", len(S))
