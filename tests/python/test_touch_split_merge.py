"""Touches that split and merge (doc/contacts.md §3, pkg/contact/TouchSelection.hpp):
a node pressing a fold into a soft piece gets a second touch when the fold
passes the feature angle and loses it when the fold closes; the ledger must
not gain or lose the springs' energy at either change.  (The YADE sphere
case is test_fuzz_regressions.py::test_a_heavy_sphere_sinking_into_a_soft_piece_keeps_the_energy_ledger.)"""
import math

import pytest

import fuzzscene


def _rubber(**kw):
    m = {"young": 1e5, "poisson": 0.0, "density": 10000.0, "xi": 0.0, "restitution": 0.99999, "friction": 0.0,
         "radiusFraction": 1.0, "law": "stableNeoHookean"}
    m.update(kw)
    return m


def _box(cells):
    return {"kind": "box", "size": [0.1, 0.1, 0.1], "cells": [cells] * 3, "tetsPerCell": 5, "convex": True}


@pytest.mark.parametrize("dtFraction", [0.225, 0.45])
def test_a_cube_corner_pressing_a_soft_face_keeps_the_ledger_as_its_touches_split_and_merge(scene, dtFraction):
    """A stiff one-cell cube (E 1e7, rho 3000, contact radius half an edge),
    a corner first (turned 54.7 deg about (1, -1, 0)), at 3 m/s onto a soft
    cube (E 1e5, rho 1e4, 2x2x2 cells, contact radius one edge, restitution
    1, no viscosity), no gravity: the corner node presses the soft top face's
    centre into a dimple whose faces fold past the 30 deg feature angle, so
    its touch with the soft cube splits in two and merges again.  The ledger
    must stay far within the first-order drift: gain 3.6e-4 and 3.8e-5 of
    the energy in flight at f = 0.45 and 0.225.  With touches born and
    dropped at full overlap it gained 0.048 at both steps (above the allowed
    0.15 f at 0.225: not first order)."""
    spec = {"threads": 1, "dtFraction": dtFraction, "steps": int(600 / dtFraction), "speed": 3.0, "approach": 0.3,
            "offset": 0.0, "offsetAngle": 0.0, "kind": "pair", "gravity": False, "direction": [0, 0, 1],
            "pieces": [{"mesh": _box(2), "material": _rubber(), "oriAxis": [0, 0, 1], "oriAngle": 0.0,
                        "spin": [0, 0, 0]},
                       {"mesh": _box(1), "material": _rubber(young=1e7, density=3000.0, radiusFraction=0.5),
                        "oriAxis": [1, -1, 0], "oriAngle": math.acos(1 / math.sqrt(3)), "spin": [0, 0, 0]}]}
    out = fuzzscene.runScene(spec)
    fuzzscene.check(out)
    assert out.contacted
    assert out.energyGain < 0.02 * dtFraction, out
