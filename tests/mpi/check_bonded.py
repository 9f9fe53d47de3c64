"""Run by tests/python/test_bonded_materials.py under mpiexec -n P: a bonded
bar of two materials (one piece spanning the ranks) set vibrating, against the
same scene stepped serially in rank 0's process.  Rank 0 prints one line
'RESULT {json}'."""
import json

import numpy as np
from mpi4py import MPI

import qdem

comm = MPI.COMM_WORLD


def scene():
    w = qdem.World()
    m = qdem.boxMesh((0.1, 0.1, 0.4), (3, 3, 12))
    z = m.nodes[m.tets].mean(axis=1)[:, 2]
    mesh = qdem.Mesh(m.nodes, m.tets, regions=np.where(z < 0, 1, 2))
    stiff = qdem.QdemMat(young=2e7, poisson=0.3, density=3000.0, viscosity=20.0, radius=0.01)
    soft = qdem.QdemMat(young=2e6, poisson=0.45, density=1000.0, viscosity=5.0, radius=0.01)
    p = w.addPiece(mesh, regionMaterials={1: stiff, 2: soft})
    p.vel[:] = 0.2 * np.random.default_rng(1).standard_normal(p.vel.shape)
    return w


def run(w):
    dt = 0.5 * w.stableDt()["combined"]
    w.core.trackEnergy = True
    w.core.step(dt, 600)


dist = scene()
dist.core.setCommunicator(comm)
run(dist)
dist.core.gatherAll()
x, v = np.array(dist.core.pos), np.array(dist.core.vel)
counts = comm.allgather(dist.core.partitionStats["ownedTets"])
if comm.rank == 0:
    ser = scene()
    run(ser)
    xs, vs = np.array(ser.core.pos), np.array(ser.core.vel)
    out = {"dx": float(np.abs(x - xs).max()), "dv": float(np.abs(v - vs).max()),
           "vmax": float(np.abs(vs).max()), "disp": float(np.abs(xs - np.array(ser.core.refPos)).max()),
           "tetsPerRank": counts, "viscous": ser.core.energy["viscous"]}
    print("RESULT " + json.dumps(out), flush=True)
