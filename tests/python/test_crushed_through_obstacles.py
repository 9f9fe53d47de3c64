"""A piece crushed through itself against a box, a facet or a two-sided wall
stops the run in the step it happens, naming the node, the obstacle, the
impact speed against the material's wave speed and the stopping distance
(doc/hard_cases.md, "Crushed through boxes and facets"): the very soft,
dense cube of test_fuzz_regressions.py's one-sided wall case, thrown at
28 m/s at half the stable step onto a floor of two facets or a box's top
face.  The obstacle holds its surface nodes (side memory pushes back the
ones pushed through) while its inner nodes, still at 28 m/s, are driven
past them and through the obstacle."""
import pytest

import fuzzscene


def _spec(obstacle, law="stableNeoHookean"):
    material = {"young": 1e5, "poisson": 0.0, "density": 10000.0, "xi": 0.0, "restitution": 0.99999,
                "friction": 0.0, "radiusFraction": 1.0, "law": law}
    mesh = {"kind": "box", "size": [0.1, 0.1, 0.1], "cells": [3] * 3, "tetsPerCell": 5, "convex": True}
    piece = {"mesh": mesh, "material": material, "oriAxis": [0, 0, 1], "oriAngle": 0.0, "spin": [0, 0, 0]}
    return {"threads": 1, "dtFraction": 0.5, "steps": 1010, "speed": 28.2, "approach": 0.35, "offset": 0.0,
            "offsetAngle": 0.0, "kind": "drop", "gravity": False, "pieces": [piece],
            "obstacle": dict(obstacle, frictionAngle=0.0), "incidence": 0.0}


@pytest.mark.parametrize("obstacle,name", [({"kind": "box"}, "box"), ({"kind": "wall", "axis": 2, "sense": 0}, "wall")])
def test_a_cube_crushed_through_a_facet_or_a_box_stops_naming_it(scene, obstacle, name):
    out = fuzzscene.runScene(_spec(obstacle))
    print(out)
    fuzzscene.check(out)
    assert out.stop is not None and "crushed through itself against the %s" % name in out.stop, out
    assert out.energyGain < 0.01, out
