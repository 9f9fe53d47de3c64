"""The stable-step report on a world split over MPI ranks: every rank names
the same limiting piece and elements (in the mesh's own numbering) as the
serial world, and a step above the limit is refused alike on every rank."""
import pytest

from mpi_launch import mpirun, python, requireMpi, result


@pytest.mark.parametrize("P", [2, 3])
def test_every_rank_names_the_serial_limiting_sliver(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_step_report.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["ranks"] == P
    s = r["serial"]
    # The slivered piece (the last one added) limits the step, by its one sliver.
    assert s["piece"] == 6 and s["elements"] == [r["sliver"]] and s["worstQuality"] < 0.05
    assert "piece 6, tetrahedra %d " % r["sliver"] in s["elementLimit"]
    # The split is real: every rank owns some tetrahedra, none owns all.
    assert all(0 < n < sum(r["owned"]) for n in r["owned"])
    for rep in r["perRank"]:
        assert rep == s  # same floats, ids, counts and words on every rank
    # 3x over the limit: the same refusal, naming the sliver, on every rank.
    assert len(set(r["refusals"])) == 1
    assert r["refusals"][0].startswith("StabilityError") and "tetrahedra %d " % r["sliver"] in r["refusals"][0]
