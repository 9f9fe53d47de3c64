"""A contact kind with history runs under MPI as serially: the test-only
bond kind nodeSpringTest (pkg/phases/NodeSpringKind.cpp, added by one file,
one row and one switch line) on 2 and 3 ranks, with the contact halo its
declared reach sizes and a forced rebalance that moves the bonds' rows with
their nodes, gives the serial bonds and trajectory (tests/mpi/check_contact_kind_history.py)."""
import pytest

from mpi_launch import mpirun, python, requireMpi, result


@pytest.mark.parametrize("P", [2, 3])
def test_bond_kind_with_history_as_serial(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_contact_kind_history.py"), timeout=240)
    assert rc == 0, "rc %d (124: timeout)\n%s" % (rc, out[-4000:])
    r = result(out)
    # Bonds form, tear and form again: the kind's history is exercised.
    assert max(r["serialSeries"]) > 0 and len(set(r["serialSeries"])) > 2, r["serialSeries"]
    # Across ranks, through the halo and the rebalance: the serial bonds ...
    assert r["series"] == r["serialSeries"]
    assert sum(r["ghosts"]) > 0 and r["movedNodes"] and r["movedNodes"][0] > 0, (r["ghosts"], r["movedNodes"])
    # ... and the serial trajectory, to rounding.
    assert r["maxDisplacement"] > 1e-4
    assert r["dx"] <= 1e-12 * r["maxDisplacement"], (r["dx"], r["maxDisplacement"])
