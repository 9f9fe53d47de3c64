"""The stable step of piece-piece contacts as they are (doc/formulation.md,
"Piece-piece contacts as they are"): each step bounds every node's contact
springs, as a node pressed on a face and as a corner carrying the other
piece's nodes, with its piece's elements; stableDt() reports it and a step
whose contacts make it below O.dt stops, named."""
import math

import pytest

import qdem
from conftest import rubber


def _pressedPair(radius, cells=2, L=0.1, press=0.5):
    """Two cubes face to face along x, node on node, their faces 2 r (1 - press)
    apart (inside the reach 2 r: the springs pressed), at rest."""
    mat = rubber(radius=radius, restitution=1.0)
    w = qdem.World()
    gap = 2 * radius * (1 - press)
    a = w.addPiece(qdem.boxMesh((L, L, L), (cells,) * 3), mat, pos=(-L / 2 - gap / 2, 0, 0))
    b = w.addPiece(qdem.boxMesh((L, L, L), (cells,) * 3), mat, pos=(L / 2 + gap / 2, 0, 0))
    return w, a, b


def test_no_contact_reports_no_limit():
    w, a, b = _pressedPair(0.002, press=-1.0)  # 4 r apart: out of reach
    w.core.trackEnergy = True
    d = w.stableDt()
    assert math.isinf(d["pieceContact"]) and d["pieceContactNode"] == -1
    w.core.step(0.5 * d["combined"], 3)
    assert math.isinf(w.stableDt()["pieceContact"])
    assert w.stableDt()["combined"] == d["combined"]


def test_a_pressed_pair_reports_the_limit_of_its_contacts():
    """A reach (2 x 5 cm) above the cell size (5 cm): each face node is
    pressed on the other face and carries the other piece's nodes on its
    triangles, and nodes beside the faces touch too.  The estimate before
    the run (one spring per node) is 1.13 x the limit of the contacts as they
    are; that limit is reported after a step and counted in `combined`.
    (That it is never above the exact step: StableStepProperty.
    PiecesRestingOnPieces; a run below it: test_fuzz_regressions.py.)"""
    w, a, b = _pressedPair(0.05)
    before = w.stableDt()
    w.core.step(1e-9 * before["combined"], 1)
    d = w.stableDt()
    assert d["pieceContact"] < before["combined"] / 1.1
    assert d["combined"] == d["pieceContact"]
    assert d["combinedExplicit"] == d["pieceContact"]
    assert "contacts on node" in d["limitedBy"]
    assert d["pieceContactPiece"] in (0, 1) and d["pieceContactNode"] >= 0


def test_a_step_above_the_contacts_limit_stops_naming_the_node():
    w, a, b = _pressedPair(0.05)
    before = w.stableDt()["combined"]
    with pytest.raises(qdem.StabilityError, match=r"contacts on node \d+ of piece [01] make its stable "
                                                  r"time step .* Lower O.dt below"):
        w.core.step(0.99 * before, 1)
