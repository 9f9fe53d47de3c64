"""Latency alpha and inverse bandwidth beta between two MPI ranks, by ping-pong
(doc/parallel_scaling.md, "Benchmark").  Run under mpiexec with 2 ranks:

    mpiexec -n 2 python3 pingpong.py --out out/bench/mpi_pingpong.json

Rank 0 sends m bytes, rank 1 sends them back; the one-way time is half the
round trip.  For each size (8 B .. 4 MB, powers of 2) several trials of many
round trips each; per size the minimum and the median over trials.  The fit
t(m) = alpha + beta * m is a least-squares fit of the per-size times weighted
by 1/t (relative residuals), so small messages fix alpha and large ones beta
instead of the large ones deciding both.  Fitted on the minima (what the
hardware can do) and on the medians (what a shared machine gives)."""
import argparse
import json
import os
import time

import numpy as np
from mpi4py import MPI


def roundTrips(comm, buf, n):
    """Seconds for n round trips of buf between ranks 0 and 1."""
    comm.Barrier()
    t0 = MPI.Wtime()
    for _ in range(n):
        if comm.rank == 0:
            comm.Send(buf, dest=1, tag=7)
            comm.Recv(buf, source=1, tag=7)
        else:
            comm.Recv(buf, source=0, tag=7)
            comm.Send(buf, dest=0, tag=7)
    return MPI.Wtime() - t0


def fit(sizes, times):
    """alpha, beta of t = alpha + beta m, least squares on relative residuals."""
    m, t = np.asarray(sizes, float), np.asarray(times, float)
    A = np.stack([1.0 / t, m / t], axis=1)
    (alpha, beta), *_ = np.linalg.lstsq(A, np.ones_like(t), rcond=None)
    rel = (alpha + beta * m - t) / t
    return float(alpha), float(beta), float(np.max(np.abs(rel)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/bench/mpi_pingpong.json")
    ap.add_argument("--trials", type=int, default=7)
    ap.add_argument("--budget", type=float, default=0.04, help="seconds per trial (about)")
    ap.add_argument("--max-bytes", type=int, default=4 << 20)
    a = ap.parse_args()
    comm = MPI.COMM_WORLD
    if comm.size != 2:
        raise SystemExit("pingpong.py needs exactly 2 ranks (mpiexec -n 2)")
    sizes = [1 << k for k in range(3, 64) if (1 << k) <= a.max_bytes]
    rows = []
    t_start = time.time()
    for m in sizes:
        buf = np.zeros(m, dtype=np.uint8)
        roundTrips(comm, buf, 3)  # warm-up: connection and buffer set up
        # Round trips per trial from one probe, agreed by both ranks.
        probe = comm.bcast(roundTrips(comm, buf, 5) / 5, root=0)
        n = int(max(3, min(20000, a.budget / max(probe, 1e-7))))
        oneWay = [roundTrips(comm, buf, n) / (2 * n) for _ in range(a.trials)]
        oneWay = comm.bcast(oneWay, root=0)
        rows.append({"bytes": m, "round_trips_per_trial": n, "trials": a.trials,
                     "one_way_s_min": float(np.min(oneWay)), "one_way_s_median": float(np.median(oneWay))})
    if comm.rank == 0:
        res = {"what": "MPI ping-pong between 2 ranks on this machine (shared memory, oversubscription-safe "
                       "settings of the caller); one-way time = round trip / 2",
               "fit": "t(m) = alpha + beta*m, least squares weighted by 1/t over all sizes",
               "load_average_before_after": None, "seconds": time.time() - t_start, "rows": rows}
        for key in ("min", "median"):
            al, be, worst = fit([r["bytes"] for r in rows], [r["one_way_s_" + key] for r in rows])
            res["alpha_s_" + key], res["beta_s_per_byte_" + key] = al, be
            res["bandwidth_GBps_" + key] = 1e-9 / be if be > 0 else None
            res["fit_worst_relative_error_" + key] = worst
        # The two ends separately: the linear law does not hold across Open
        # MPI's switch from eager to rendezvous sends (a step near 4 KB here).
        small = [r for r in rows if r["bytes"] <= 1024]
        large = [r for r in rows if r["bytes"] >= 65536]
        res["alpha_s_small_messages_min"] = float(np.mean([r["one_way_s_min"] for r in small]))
        if len(large) >= 2:
            res["beta_s_per_byte_large_messages_min"] = float(np.polyfit(
                [r["bytes"] for r in large], [r["one_way_s_min"] for r in large], 1)[0])
        res["load_average_after"] = os.getloadavg()
        res.pop("load_average_before_after")
        res["env"] = {k: os.environ.get(k) for k in ("OMPI_MCA_mpi_yield_when_idle", "OMP_NUM_THREADS")}
        os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
        with open(a.out, "w") as f:
            json.dump(res, f, indent=1)
        print("pingpong: alpha %.3g s (median %.3g), beta %.3g s/B = %.2f GB/s (median %.2f GB/s); fit worst %.0f%%; "
              "wrote %s" % (res["alpha_s_min"], res["alpha_s_median"], res["beta_s_per_byte_min"],
                            res["bandwidth_GBps_min"] or 0, res["bandwidth_GBps_median"] or 0,
                            100 * res["fit_worst_relative_error_min"], a.out))


if __name__ == "__main__":
    main()
