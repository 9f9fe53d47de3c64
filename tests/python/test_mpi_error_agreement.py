"""An error raised on one MPI rank only, before phases that hold collectives
(the sleep phase's reductions, the implicit viscous solve's sums), stops
every rank within seconds with the same message naming the failing rank and
the original error: the failing rank still runs the step's later phases and
exchanges, and the end-of-step reduction carries the error flag.  (Both
cases waited for the failed rank until mpirun's timeout before.)"""
import pytest

from mpi_launch import mpirun, python, requireMpi, result


@pytest.mark.parametrize("P", [2, 3])
def test_rank_local_error_stops_every_rank_in_seconds(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_error_agreement.py"), timeout=90)
    assert rc == 0, "rc %d (124: a rank waited for a failed one until the timeout)\n%s" % (rc, out[-4000:])
    caught = result(out)["caught"]
    assert len(caught) == P
    for case, kind, words in (("sleepNan", "StabilityError", "not finite"),
                              ("implicitOverlap", "ValueError", "starts inside obstacle")):
        msgs = {(c[case][0], c[case][1]) for c in caught}
        assert len(msgs) == 1, (case, msgs)  # the same error on every rank
        k, msg = msgs.pop()
        assert k == kind and words in msg and msg.startswith("QDEM rank "), (case, k, msg)
        assert max(c[case][2] for c in caught) < 30, case  # seconds, not a timeout
    # The NaN was on the last rank's node: that rank is named.
    assert caught[0]["sleepNan"][1].startswith("QDEM rank %d of %d" % (P - 1, P))
