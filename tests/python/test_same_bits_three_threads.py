"""Three and four QDEM threads give the same bits run after run, energy ledger
included.  OpenMP's reduction(+) adds the threads' partial sums in the order
the threads finish, so with three threads or more an energy booked by a
contact, element or integration loop came out a few ulp apart between two
runs of one script (the forces and positions did not: they go through
per-thread buffers summed in thread order).  The loops now write their
partials per thread and add them in thread order (pkg/core/ThreadPartials.hpp).

The machine may have fewer cores than threads: oversubscribed threads finish
in a more random order, which is what this test needs."""
import sys
from pathlib import Path

import numpy as np
import pytest

from qdem import _core

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "mpi"))
import scenes  # noqa: E402  (tests/mpi/scenes.py: the MPI tests' scenes)


def _run(threads):
    _core.setThreads(threads)
    try:
        w = scenes.withContacts()
        w.core.localDamping = 0.2
        dt = 0.5 * w.stableDt()["combined"]
        contacts = 0
        for _ in range(30):
            w.core.step(dt, 10)
            contacts += w.core.contactCounts["pointPolygon"] + w.core.contactCounts["edgeEdge"]
        return dict(w.core.energy), np.array(w.core.pos, copy=True), contacts
    finally:
        _core.setThreads(0)


@pytest.mark.parametrize("threads", [3, 4])
def test_runs_at_three_or_four_threads_give_the_same_energy_bits(threads):
    first, pos0, n0 = _run(threads)
    assert n0 > 0, "the pieces must touch"
    booked = [k for k, v in first.items() if v != 0.0]
    assert {"contactDamping", "friction", "viscous"} & set(booked), booked
    for trial in range(5):
        again, pos, n = _run(threads)
        assert n == n0 and np.array_equal(pos, pos0)
        differ = {k: (first[k], again[k]) for k in first if first[k] != again[k]}
        assert not differ, "run %d at %d threads: energy terms differ in their last bits: %s" % (
            trial + 2, threads, {k: "%.17g vs %.17g" % v for k, v in differ.items()})
