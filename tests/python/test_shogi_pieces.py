"""Shogi piece generator (seed §5): shape, proportions and meshes."""
import math

import numpy as np
import pytest

import qdem
from qdem import shogi


def _angles(p):
    out = []
    for i in range(5):
        a, b, c = p[i - 1], p[i], p[(i + 1) % 5]
        u, v = a - b, c - b
        out.append(math.degrees(math.acos(u @ v / np.linalg.norm(u) / np.linalg.norm(v))))
    return out


@pytest.mark.parametrize("kind", shogi.ORDER)
def test_outline_has_the_shogi_angles_and_size(kind):
    h, w, t = shogi.KINDS[kind]
    p = shogi.outline(h, w)
    assert np.allclose(sorted(_angles(p)), [81, 81, 117, 117, 144], atol=1e-9)
    assert p[:, 1].max() == pytest.approx(h) and np.ptp(p[:, 0]) == pytest.approx(w)


def test_sizes_run_from_king_to_pawn():
    assert shogi.KINDS["king"] == pytest.approx((32.0, 28.7, 9.7))
    assert shogi.KINDS["pawn"] == pytest.approx((27.0, 22.5, 7.75))
    heights = [shogi.KINDS[k][0] for k in shogi.ORDER]
    assert heights == sorted(heights, reverse=True)
    assert len(shogi.SET) == 20 and shogi.SET.count("pawn") == 9


@pytest.mark.parametrize("kind", ["king", "gold", "pawn"])
def test_meshed_pieces_are_valid_with_the_seeds_counts(kind):
    m = shogi.mesh(kind)
    assert (m.volumes() > 0).all()
    m.check()                                            # closed, manifold surface
    assert m.nNodes == pytest.approx(797, rel=0.10)
    assert m.nTets == pytest.approx(2566, rel=0.10)
    assert m.volumes().sum() == pytest.approx(shogi.volume(kind), rel=0.01)
    lo, hi = m.bounds()
    h, w, t = (v * 1e-3 for v in shogi.KINDS[kind])
    assert hi - lo == pytest.approx([w, h, t], rel=0.01)   # proportions of the kind
    # thinner at the top: thickness near the apex vs near the base
    top = m.nodes[:, 1] > 0.95 * h
    base = m.nodes[:, 1] < 0.05 * h
    assert np.ptp(m.nodes[top, 2]) < 0.8 * np.ptp(m.nodes[base, 2])
