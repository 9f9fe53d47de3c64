"""Run by tests/python/test_mpi_step_report.py under mpiexec -n P: the
stable-step report (stableDt()'s limiting piece, elements in its mesh's
numbering, counts and quality) with a slivered piece among the split world's
pieces, on every rank against serial; and a step above the limit refused
alike on every rank (no rank left waiting).  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

from mpi4py import MPI

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "python"))
import scenes  # noqa: E402
from test_mesh_step_report import _slivered_box  # noqa: E402

import warnings  # noqa: E402

import qdem  # noqa: E402

warnings.simplefilter("ignore")  # the sliver warning, once per rank: the report is what is compared

comm = MPI.COMM_WORLD
KEYS = ("combined", "piece", "elements", "elementsNearLimit", "worstQuality", "elementLimit")


def build():
    w = scenes.withContacts()
    mesh, sliver = _slivered_box()
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004)
    w.addPiece(mesh, mat, pos=(1.2, 0.0, 0.5))  # far along x: the split puts it on the last ranks
    return w, sliver


def report(w):
    d = w.stableDt()
    return {k: d[k] for k in KEYS}


serialWorld, sliver = build()
serial = report(serialWorld)
w, _ = build()
w.core.setCommunicator(comm)
dt = 0.5 * serial["combined"]
w.core.step(dt, 20)
ranks = comm.gather(report(w), root=0)
owned = comm.gather(int(w.core.partitionStats["ownedTets"]), root=0)
# The sliver's piece: which ranks own any of its tetrahedra.
# Above the limit: every rank refuses the same step with the same words.
try:
    w.core.checkDt(3.0 * serial["combined"])
    refused = ""
except Exception as e:  # noqa: BLE001 (the message is what is compared)
    refused = "%s: %s" % (type(e).__name__, e)
refusals = comm.gather(refused, root=0)
if comm.rank == 0:
    print("RESULT " + json.dumps({"ranks": comm.size, "sliver": sliver, "serial": serial, "perRank": ranks,
                                  "owned": owned, "refusals": refusals}), flush=True)
