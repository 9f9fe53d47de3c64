"""The run-time stable step of the piece-piece contacts as they are under MPI
(doc/formulation.md, "Piece-piece contacts as they are"): the ranks' shares
of each node's contact load go to its owner with the forces, the owners take
the limit, the end-of-step reduction carries the smallest; so every rank
reports the serial limit, node and piece, and stops in the serial step with
the serial message."""
import math

import pytest

from mpi_launch import mpirun, python, requireMpi, result


@pytest.mark.parametrize("P", [2, 3])
def test_contact_step_limit_and_stop_as_serial(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_contact_step.py"), timeout=180)
    assert rc == 0, "rc %d (124: timeout)\n%s" % (rc, out[-4000:])
    r = result(out)
    s = r["serial"]
    # (a) pressed cubes: a finite limit below the estimate before the run.
    assert math.isfinite(s["limit"]["pieceContact"]) and s["limit"]["pieceContactNode"] >= 0
    assert len(r["perRank"]) == P
    for rank in r["perRank"]:
        d = rank["limit"]
        assert d["pieceContact"] == pytest.approx(s["limit"]["pieceContact"], rel=1e-12)
        assert d["combined"] == pytest.approx(s["limit"]["combined"], rel=1e-12)
        for k in ("pieceContactNode", "pieceContactPiece"):
            assert d[k] == s["limit"][k], k
    # (b) thrown cubes at 0.9 of the estimate before the run: stopped serially
    # by their contacts as they are, and on every rank in the same step with
    # the same message.
    assert s["stop"]["stopped"], s["stop"]
    assert "contacts on node" in s["stop"]["message"]
    for rank in r["perRank"]:
        st = rank["stop"]
        assert st["stopped"] and st["message"] == s["stop"]["message"], (st, s["stop"])
        # (Under MPI the stop comes at the end of that step, after its integration.)
        assert st["iter"] == s["stop"]["iter"] + 1
    # (c) pieces asleep beside awake ones: their nodes' stale rows are not
    # counted; the serial limit on every rank.
    assert s["sleeping"]["asleep"] > 0 and math.isfinite(s["sleeping"]["pieceContact"]), s["sleeping"]
    for rank in r["perRank"]:
        d = rank["sleeping"]
        assert "stopped" not in d, d
        assert d["asleep"] == s["sleeping"]["asleep"]
        assert d["pieceContact"] == pytest.approx(s["sleeping"]["pieceContact"], rel=1e-6)
        assert d["pieceContactNode"] == s["sleeping"]["pieceContactNode"]
