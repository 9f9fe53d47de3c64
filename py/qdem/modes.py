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
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError("naturalFrequencies: count=%r is invalid: give a whole number >= 1" % (count,))
    m = asMesh(mesh)
    lam, mu = lame(material)
    rows, cols, vals, lumped = _stiffness(m.nodes, m.tets.astype(np.int64), lam, mu)
    n = 3 * len(m.nodes)
    minv = 1.0 / np.sqrt(np.repeat(lumped * float(material.density), 3))
    # Solved in units of the largest diagonal entry of M^-1/2 K M^-1/2 (~ (c/h)^2):
    # a 1 cm steel cube has omega^2 ~ 1e13, and a shift or a zero threshold in
    # absolute units (the former sigma = -1) made shift-invert return rigid modes
    # as elastic ones and negative omega^2.  In these units the rigid modes are
    # zero to ~1e-13 and the lowest elastic one is ~(h/L)^2 >> 1e-9.
    diag = np.zeros(n)
    np.add.at(diag, rows[rows == cols], vals[rows == cols])
    scale = float(np.max(diag * minv * minv))
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError("naturalFrequencies: the stiffness is not finite and positive "
                         "(young=%g, poisson=%g, density=%g): check the material"
                         % (material.young, material.poisson, material.density))
    zero = 1e-9
    if n <= 2000:
        K = np.zeros((n, n))
        np.add.at(K, (rows, cols), vals)
        w2 = np.linalg.eigvalsh(minv[:, None] * (K / scale) * minv[None, :])
    else:
        import scipy.sparse as sp
        import scipy.sparse.linalg as sla
        K = sp.coo_matrix((vals / scale, (rows, cols)), shape=(n, n)).tocsc()
        A = sp.diags(minv) @ K @ sp.diags(minv)
        k = min(count + 6, n - 2)
        while True:
            # Shift-invert about a small negative shift: the eigenvalues nearest it
            # are the lowest ones, rigid modes first, and A - sigma I is positive definite.
            w2 = np.sort(sla.eigsh(A, k=k, sigma=-1e-6, which="LM", return_eigenvectors=False))
            if np.count_nonzero(w2 > zero) >= count or k >= n - 2:
                break
            k = min(2 * k, n - 2)   # more rigid modes than six: a mesh of several parts
    w2 = np.sort(np.asarray(w2))
    if w2[0] < -zero:
        raise RuntimeError("naturalFrequencies: the eigen-solver returned omega^2 = %.3g < 0 "
                           "(in units of %.3g): the mesh or the material is degenerate"
                           % (w2[0], scale))
    elastic = w2[w2 > zero]
    if len(elastic) < count:
        raise ValueError("naturalFrequencies: the mesh has %d elastic modes, %d asked for"
                         % (len(elastic), count))
    return np.sqrt(elastic[:count] * scale)


def _modeIndex(mode):
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode < 0:
        raise ValueError("mode=%r is invalid: give 0 for the first elastic mode, 1 for the next, ..." % (mode,))
    return int(mode)


def viscosityForDamping(mesh, material, dampingRatio, mode=0):
    """The QdemMat.viscosity [Pa s] that gives elastic mode ``mode`` (0 = the
    first) of the free piece the damping ratio ``dampingRatio``:
    eta = mu * 2 xi / omega."""
    xi = float(dampingRatio)
    if not (xi >= 0 and np.isfinite(xi)):
        raise ValueError("viscosityForDamping: dampingRatio=%r is invalid: give a finite number >= 0 "
                         "(0.1 is a tenth of critical damping)" % (dampingRatio,))
    omega = naturalFrequencies(mesh, material, _modeIndex(mode) + 1)[mode]
    return lame(material)[1] * 2.0 * xi / omega


def dampingRatio(mesh, material, mode=0):
    """Damping ratio beta*omega/2 of elastic mode ``mode`` with the material's viscosity."""
    omega = naturalFrequencies(mesh, material, _modeIndex(mode) + 1)[mode]
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
