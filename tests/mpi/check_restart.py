"""Run by tests/python/test_mpi.py under mpiexec -n P: a run on P ranks
saved mid-run (qdem.saveState: every rank calls it, rank 0 writes) and
continued, against the same restart of a serial run.  Rank 0 prints
'RESULT {json}'."""
import json
import os
import sys
import tempfile

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qdem  # noqa: E402
import scenes  # noqa: E402

comm = MPI.COMM_WORLD
N = 200
path = os.path.join(os.environ.get("QDEM_MPI_TMP", tempfile.gettempdir()), "qdem_mpi_restart_%d.npz" % comm.size)

# P ranks: N steps, save, N more; then a fresh world loads the file and goes on N steps.
w = scenes.withContacts()
w.core.setCommunicator(comm)
dt = 0.5 * w.stableDt()["combined"]
w.core.step(dt, N)
qdem.saveState(path, world=w)
w.core.step(dt, N)
w.core.gatherAll()
xCont = np.array(w.core.pos)
comm.Barrier()  # the file is written
r = scenes.withContacts()
qdem.loadState(path, world=r)
r.core.setCommunicator(comm)
r.core.step(dt, N)
r.core.gatherAll()
xRest = np.array(r.core.pos)
eRest = r.core.energy["total"]
if comm.rank == 0:
    # The file is the serial one: one process loads it and goes on alike.
    one = scenes.withContacts()
    qdem.loadState(path, world=one)
    one.core.step(dt, N)
    xOne = np.array(one.core.pos)
    s = scenes.withContacts()
    s.core.step(dt, 2 * N)
    x0 = scenes.withContacts().core.pos
    xs = np.array(s.core.pos)
    d = float(np.abs(xs - x0).max())
    print("RESULT " + json.dumps({"ranks": comm.size, "disp": d, "contVsSerial": float(np.abs(xCont - xs).max()),
                                  "restartVsCont": float(np.abs(xRest - xCont).max()),
                                  "serialRestartVsCont": float(np.abs(xOne - xCont).max()),
                                  "energySerialRestart": one.core.energy["total"],
                                  "energyRestart": eRest, "energyCont": w.core.energy["total"],
                                  "energySerial": s.core.energy["total"]}), flush=True)
    os.remove(path)
