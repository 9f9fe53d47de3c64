"""Natural frequencies of a free QDEM piece, and the viscosity that gives a
mode a chosen damping ratio.

The linearised element (small strain about the reference shape, the tangent
every law in qdem shares there) with the lumped mass QDEM integrates:
K u = omega^2 M u.  Six zero frequencies are the rigid motions; the next is
the piece's first elastic mode.  The Kelvin-Voigt viscosity of QdemMat is
stiffness-proportional (C = beta K, beta = eta/mu: doc/formulation.md), so
each mode has the damping ratio xi = beta*omega/2 (Rayleigh damping with a
stiffness term only).

For meshes up to a few thousand nodes (dense eigen-solve below 2,000 degrees
of freedom, SciPy's sparse shift-invert Lanczos above)."""


import numpy as np

from .mesh import asMesh


def _stiffness(nodes, tets, lam, mu):
    """Assembled linear stiffness (sparse COO triplets) and lumped masses / rho."""
    x = nodes[tets]                                   # (T, 4, 3)
    D = (x[:, 1:, :] - x[:, :1, :]).transpose(0, 2, 1)  # columns: edge vectors
    vol = np.linalg.det(D) / 6.0
    Binv = np.linalg.inv(D)                            # rows: grad N_1..3
    G = np.concatenate([-Binv.sum(axis=1, keepdims=True), Binv], axis=1)  # (T, 4, 3)
    # K_ab,ij = V (lam g_ai g_bj + mu g_aj g_bi + mu (g_a . g_b) delta_ij)
    gg = np.einsum("tai,tbi->tab", G, G)
    Ke = (lam * np.einsum("tai,tbj->taibj", G, G) + mu * np.einsum("taj,tbi->taibj", G, G)
          + mu * np.einsum("tab,ij->taibj", gg, np.eye(3))) * vol[:, None, None, None, None]
    dof = (3 * tets[:, :, None] + np.arange(3)[None, None, :]).reshape(len(tets), 12)
    rows = np.repeat(dof, 12, axis=1).ravel()
    cols = np.tile(dof, (1, 12)).ravel()
    lumped = np.zeros(len(nodes))
    np.add.at(lumped, tets.ravel(), np.repeat(vol / 4.0, 4))
    return rows, cols, Ke.reshape(len(tets), 12, 12).ravel(), lumped


def lame(material):
    """Lame constants (lambda, mu) [Pa] of a QdemMat."""
    nu, E = float(material.poisson), float(material.young)
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def naturalFrequencies(mesh, material, count=6):
    """The ``count`` lowest non-zero angular frequencies [rad/s] of the free
    piece (mesh in any form addPiece takes; material a QdemMat), rigid modes
    left out, ascending."""
    m = asMesh(mesh)
    lam, mu = lame(material)
    rows, cols, vals, lumped = _stiffness(m.nodes, m.tets.astype(np.int64), lam, mu)
    n = 3 * len(m.nodes)
    minv = 1.0 / np.sqrt(np.repeat(lumped * float(material.density), 3))
    want = count + 6
    if n <= 2000:
        K = np.zeros((n, n))
        np.add.at(K, (rows, cols), vals)
        w2 = np.linalg.eigvalsh(minv[:, None] * K * minv[None, :])
    else:
        import scipy.sparse as sp
        import scipy.sparse.linalg as sla
        K = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsc()
        A = sp.diags(minv) @ K @ sp.diags(minv)
        w2 = sla.eigsh(A, k=min(want, n - 1), sigma=-1.0, which="LM", return_eigenvectors=False)
    w2 = np.sort(np.asarray(w2))
    scale = max(abs(w2[-1]), 1e-300)
    elastic = w2[w2 > 1e-9 * scale]
    return np.sqrt(elastic[:count])


def viscosityForDamping(mesh, material, dampingRatio, mode=0):
    """The QdemMat.viscosity [Pa s] that gives elastic mode ``mode`` (0 = the
    first) of the free piece the damping ratio ``dampingRatio``:
    eta = mu * 2 xi / omega."""
    omega = naturalFrequencies(mesh, material, mode + 1)[mode]
    return lame(material)[1] * 2.0 * float(dampingRatio) / omega


def dampingRatio(mesh, material, mode=0):
    """Damping ratio beta*omega/2 of elastic mode ``mode`` with the material's viscosity."""
    omega = naturalFrequencies(mesh, material, mode + 1)[mode]
    return float(material.viscosity) / lame(material)[1] * omega / 2.0


def modeShape(mesh, material, omega):
    """The free vibration mode of the piece (dense solve: meshes of up to a
    few thousand nodes) whose angular frequency is nearest ``omega`` [rad/s]:
    (shape, nodeMass), the displacement shape per node (n, 3) in the mesh's
    node order and the lumped node masses [kg] (n,)."""
    m = asMesh(mesh)
    lam, mu = lame(material)
    rows, cols, vals, lumped = _stiffness(m.nodes, m.tets.astype(np.int64), lam, mu)
    n = 3 * len(m.nodes)
    K = np.zeros((n, n))
    np.add.at(K, (rows, cols), vals)
    minv = 1 / np.sqrt(np.repeat(lumped * float(material.density), 3))
    w2, V = np.linalg.eigh(minv[:, None] * K * minv[None, :])
    k = np.argmin(np.abs(np.sqrt(np.abs(w2)) - omega))
    return (minv * V[:, k]).reshape(-1, 3), lumped * float(material.density)


__all__ = ["lame", "naturalFrequencies", "viscosityForDamping", "dampingRatio", "modeShape"]
