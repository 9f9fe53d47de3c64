"""Weak-scaling model of QDEM under MPI to 16,384 ranks (doc/parallel_scaling.md,
"Weak-scaling model").

Time of one step on the slowest rank of P, each rank holding ~50,000 nodes:

    T(P) = w * tetsMax(P)                       work: measured ns per tet (P = 1 run)
         + alpha * messages(P)                   2 per neighbour (force back, states forward)
         + beta * bytes(P)                       max over ranks of bytes sent or received
         + 2 log2(P) (alpha + beta * 8 n)        the end-of-step tree reduction of n doubles
    E(P) = T1(P) / T(P)                         T1(P) = w * tets/P: the mean share alone

tetsMax, neighbours and bytes come from the real partitioner
(build/mpi_partition_model, its JSON) up to the P it reaches; beyond it
they are extrapolated by fits to its rows (fitHilbert, fitSlabs), checked by
fitting on part of the rows and predicting the rest.  alpha and beta come
from pingpong.py, w from run_ranks.py.  The model is validated on the
measured P = 2..4 runs: their bytes and messages per rank must equal what the
halo rule predicts from the run's own partition (node owners saved by
run_ranks.py), and their times are compared.

    python3 model.py --pingpong out/bench/mpi_pingpong.json --ranks out/bench/mpi_ranks.json \
        --partition out/bench/mpi_partition.json [--partition-more bench/logs/mpi_partition_512.json] \
        --out out/bench/mpi_model.json --img out/bench/img
"""
import argparse
import json
import math
import os

import numpy as np

P_MAX = 16384
DOUBLE = 8
# Doubles each rank contributes to the end-of-step reduction (Domain::finishStep):
# the error flag, force and torque of each obstacle (one floor here), 10
# energies, the load (summed) and the load again (maximised).
GATHER_DOUBLES = 1 + 6 * 1 + 10 + 2


# ---- the halo rule (Domain / Partition.hpp), from a partition --------------------------------

def predictHalo(owner, tets, P):
    """Per rank, from the node owners and the tets alone: owned nodes and tets
    (a tet is computed by the lowest owner of its nodes), ghosts (nodes of its
    tets owned by others), neighbours, and what it sends per step: its ghosts'
    partial forces (3 doubles each) and the positions and velocities of its
    nodes others read (6 doubles each), one message per neighbour and
    exchange."""
    owner = np.asarray(owner, dtype=np.int64)
    tets = np.asarray(tets, dtype=np.int64)
    tetOwner = owner[tets].min(axis=1)
    # (reader rank, node) pairs: every node of a tet read by the tet's owner
    pairs = np.unique(np.stack([np.repeat(tetOwner, 4), tets.ravel()], axis=1), axis=0)
    ghost = pairs[owner[pairs[:, 1]] != pairs[:, 0]]  # reader, node owned by another rank
    out = []
    for r in range(P):
        mineGhost = ghost[ghost[:, 0] == r][:, 1]                # nodes r reads from others
        readByOthers = ghost[owner[ghost[:, 1]] == r]            # (reader, my node)
        nbrs = set(owner[mineGhost].tolist()) | set(readByOthers[:, 0].tolist())
        sent = len(readByOthers)                                 # one (reader, node) pair = one node sent
        out.append({"rank": r, "ownedNodes": int(np.sum(owner == r)), "ownedTets": int(np.sum(tetOwner == r)),
                    "ghosts": int(len(mineGhost)), "neighbours": sorted(int(n) for n in nbrs),
                    "stepBytes": int(3 * DOUBLE * len(mineGhost) + 6 * DOUBLE * sent),
                    "stepBytesReceived": int(6 * DOUBLE * len(mineGhost) + 3 * DOUBLE * sent),
                    "stepMessages": 2 * len(nbrs)})
    return out


def commSeconds(alpha, beta, messages, bytes_, P, tree=False):
    """Halo exchanges plus the end-of-step allgather (recursive doubling: log2 P
    latencies, (P - 1) blocks of bytes).  tree: the same sums by a reduction
    in a fixed tree order instead (still deterministic; up and down the tree:
    2 log2 P latencies, each with one block)."""
    if P <= 1:
        coll = 0.0
    elif tree:
        coll = 2 * math.log2(P) * (alpha + beta * DOUBLE * GATHER_DOUBLES)
    else:
        coll = alpha * math.log2(P) + beta * DOUBLE * GATHER_DOUBLES * (P - 1)
    return alpha * messages + beta * bytes_ + coll, coll


# ---- extrapolation of the partition figures beyond the P the partitioner reached ------------

QUANTITIES = ("halo_over_owned_mean", "halo_over_owned_max", "neighbours_max", "bytes_max")


def rowValue(row, q):
    if q == "bytes_max":
        return max(row["bytes_sent_per_step_max"], row["bytes_received_per_step_max"])
    return row[q]


def fitHilbert(Ps, ys):
    """q(P) = q_inf + b P^(-1/3): a rank's share keeps its size and shape
    statistics under weak scaling, so its halo tends to a constant; ranks on
    the boundary of the scene (fewer neighbours) are a fraction ~P^(-1/3)."""
    x = np.asarray(Ps, float) ** (-1.0 / 3.0)
    A = np.stack([np.ones_like(x), x], axis=1)
    (qi, b), *_ = np.linalg.lstsq(A, np.asarray(ys, float), rcond=None)
    return {"form": "q_inf + b*P^(-1/3)", "q_inf": float(qi), "b": float(b)}


def fitSlabs(Ps, ys):
    """q(P) = a P^k on the last three P: a slab of a scene whose side grows as
    P^(1/3) is P^(-2/3) thick in units of the share, so its halo over owned
    grows as P^(2/3) while it is thicker than a layer of nodes; thinner, the
    partitioner orders the nodes of one plane by id (equal keys) and the
    slab becomes a strip, whose halo grows slower.  So the local slope of the
    largest P is carried on (k fitted, not imposed), not the whole range."""
    Ps, ys = list(Ps)[-3:], list(ys)[-3:]
    ys = np.maximum(np.asarray(ys, float), 1e-12)
    k, la = np.polyfit(np.log(np.asarray(Ps, float)), np.log(ys), 1)
    return {"form": "a*P^k", "a": float(math.exp(la)), "k": float(k)}


def evalFit(f, P):
    if f["form"].startswith("q_inf"):
        return f["q_inf"] + f["b"] * P ** (-1.0 / 3.0)
    return f["a"] * P ** f["k"]


def fitFor(method):
    return fitHilbert if method == "hilbert" else fitSlabs


def series(rows, scene, method):
    return sorted((r for r in rows if r["scene"] == scene and r["method"] == method), key=lambda r: r["ranks"])


def extrapolate(rows, scene, method, fitFrom=8):
    """Fits of each quantity on the rows with P >= fitFrom, and a check: the
    same fit made on the rows up to a quarter of the largest P predicts the
    larger ones (relative error per P), where the partitioner ran both."""
    s = series(rows, scene, method)
    use = [r for r in s if r["ranks"] >= fitFrom]
    Pmax = s[-1]["ranks"]
    fits, check = {}, {}
    for q in QUANTITIES:
        fits[q] = fitFor(method)([r["ranks"] for r in use], [rowValue(r, q) for r in use])
        part = [r for r in use if r["ranks"] <= Pmax // 4]
        if len(part) >= 2:
            f = fitFor(method)([r["ranks"] for r in part], [rowValue(r, q) for r in part])
            used = [r["ranks"] for r in part][-3:] if method == "slabs" else [r["ranks"] for r in part]
            check[q] = {"fitted_on_P": used,
                        "predicted_vs_partitioner": {str(r["ranks"]): {
                            "predicted": evalFit(f, r["ranks"]), "partitioner": rowValue(r, q),
                            "relative_error": evalFit(f, r["ranks"]) / max(rowValue(r, q), 1e-12) - 1}
                            for r in s if r["ranks"] > Pmax // 4}}
    # Imbalance: a share keeps its size, so the piece granularity that sets it
    # does not change: the worst seen at P >= 16 is carried on.
    imb = max(r["imbalance"] for r in s if r["ranks"] >= min(16, Pmax))
    usedAll = [r["ranks"] for r in use][-3:] if method == "slabs" else [r["ranks"] for r in use]
    return {"fits": fits, "check_on_overlap": check, "imbalance_beyond": imb, "fitted_on_P": usedAll}


def partitionAt(rows, ext, scene, method, P):
    """Partition figures at P: the partitioner's row when it ran that far, else the fits."""
    for r in series(rows, scene, method):
        if r["ranks"] == P:
            return {"source": "partitioner", "imbalance": r["imbalance"], "tets_per_rank": r["tets"] / P,
                    **{q: rowValue(r, q) for q in QUANTITIES}}
    s = series(rows, scene, method)
    tetsPerRank = s[-1]["tets"] / s[-1]["ranks"]
    f = {q: max(0.0, evalFit(ext["fits"][q], P)) for q in QUANTITIES}
    if method == "slabs":
        # A slab thinner than one layer of elements reads ~1/thickness slabs on
        # each side: at least 2 ceil(halo/owned) neighbours.
        f["neighbours_max"] = max(f["neighbours_max"], s[-1]["neighbours_max"], 2 * math.ceil(f["halo_over_owned_max"]))
    else:
        f["neighbours_max"] = max(f["neighbours_max"], 1.0)
    return {"source": "fit", "imbalance": ext["imbalance_beyond"], "tets_per_rank": tetsPerRank, **f}


# ---- the projection ------------------------------------------------------------------------

def pingpongCurve(pp):
    """One-way seconds for an m-byte message, interpolated (log-log) in the
    measured ping-pong minima: the straight line alpha + beta m misses the
    eager/rendezvous step, and the halo messages sit right on it."""
    m = np.log([r["bytes"] for r in pp["rows"]])
    t = np.log([r["one_way_s_min"] for r in pp["rows"]])
    return lambda size: float(np.exp(np.interp(math.log(max(size, 8.0)), m, t)))


def project(rows, exts, nsPerTet, alpha, beta, scenes, tree=False, curve=None):
    """The projection to P_MAX.  curve: the halo messages costed by the
    measured ping-pong curve (messages x time of the mean message) instead
    of alpha and beta."""
    # Powers of 2, and the seed's 5,120 cores.
    Ps = sorted([1 << k for k in range(0, int(math.log2(P_MAX)) + 1)] + [5120])
    out = {}
    for scene in scenes:
        for method in ("hilbert", "slabs"):
            pts = []
            for P in Ps:
                pa = partitionAt(rows, exts[scene][method], scene, method, P)
                work = nsPerTet * pa["imbalance"] * pa["tets_per_rank"]
                msgs = 2 * math.ceil(pa["neighbours_max"])
                comm, coll = commSeconds(alpha, beta, msgs, pa["bytes_max"], P, tree) if P > 1 else (0.0, 0.0)
                if curve and P > 1 and msgs > 0:
                    comm = msgs * curve(pa["bytes_max"] / msgs) + coll
                T = work + comm
                # The scenes' shares are 50,000 nodes only to rounding (a cube's side is
                # an integer): the ideal is the mean share of this P computed alone.
                t1 = nsPerTet * pa["tets_per_rank"]
                pts.append({"P": P, "source": pa["source"], "imbalance": pa["imbalance"],
                            "halo_over_owned_mean": pa["halo_over_owned_mean"],
                            "halo_over_owned_max": pa["halo_over_owned_max"], "neighbours_max": pa["neighbours_max"],
                            "bytes_max": pa["bytes_max"], "messages": msgs, "work_s": work,
                            "halo_s": comm - coll, "collective_s": coll, "step_s": T, "efficiency": t1 / T})
            out["%s/%s" % (scene, method)] = pts
    return out


# ---- validation on the measured runs -------------------------------------------------------

def validate(ranksJson, baseDir, nsPerTet, nsPerTetMin, alpha, beta, alphaYield, betaYield):
    out = []
    for run in ranksJson["runs"]:
        P = run["P"]
        if P < 2:
            continue
        d = np.load(os.path.join(baseDir, run["npz"]))
        pred = predictHalo(d["nodeOwner"], d["tets"], P)
        ranks = []
        exact = True
        for m, p in zip(sorted(run["ranks"], key=lambda x: x["rank"]), pred):
            same = {k: m[k] == p[k] for k in ("ownedNodes", "ownedTets", "ghosts", "neighbours", "stepBytes",
                                              "stepMessages")}
            exact = exact and all(same.values())
            b = max(p["stepBytes"], p["stepBytesReceived"])
            comm, _ = commSeconds(alpha, beta, p["stepMessages"], b, P)
            commY, _ = commSeconds(alphaYield, betaYield, p["stepMessages"], b, P)
            ranks.append({"rank": p["rank"], "measured": {k: m[k] for k in same}, "predicted": {k: p[k] for k in same},
                          "equal": same,
                          "step_s_measured_median": m["stepSeconds"]["median"],
                          "step_s_measured_min": m["stepSeconds"]["min"],
                          "step_s_model": nsPerTet * p["ownedTets"] + comm,
                          "step_s_model_yield": nsPerTet * p["ownedTets"] + commY,
                          "step_s_model_from_min": nsPerTetMin * p["ownedTets"] + comm,
                          "exchange_s_measured_median": m["exchangeSeconds"]["median"],
                          "exchange_s_measured_min": m["exchangeSeconds"]["min"],
                          "exchange_s_model_busy_poll": comm, "exchange_s_model_yield": commY})
        tets = [p["ownedTets"] for p in pred]
        out.append({"P": P, "halo_counts_exact": exact,
                    "imbalance_predicted": max(tets) / (sum(tets) / P), "imbalance_measured": run["ranks"][0]["imbalance"],
                    "load_average_before": run["loadAverageBefore"][0], "load_average_after": run["loadAverageAfter"][0],
                    "oversubscribed": P > 2, "ranks": ranks,
                    "step_s_model_max": max(r["step_s_model"] for r in ranks),
                    "step_s_model_yield_max": max(r["step_s_model_yield"] for r in ranks),
                    "step_s_model_from_min_max": max(r["step_s_model_from_min"] for r in ranks),
                    "step_s_measured_median_max": max(r["step_s_measured_median"] for r in ranks),
                    "step_s_measured_min_max": max(r["step_s_measured_min"] for r in ranks)})
    return out


# ---- plots ---------------------------------------------------------------------------------

def plots(proj, rows, imgDir, scenes):
    """parallel_efficiency.png and parallel_halo.png in imgDir, drawn as the
    site draws them from the kept JSON (scripts/bench/perf_plots.py)."""
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    import perf_plots
    os.makedirs(imgDir, exist_ok=True)
    perf_plots.drawMpiEfficiency(proj, os.path.join(imgDir, "parallel_efficiency.png"))
    perf_plots.drawMpiHalo(proj, os.path.join(imgDir, "parallel_halo.png"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pingpong", default="out/bench/mpi_pingpong.json")
    ap.add_argument("--pingpong-yield", default="out/bench/mpi_pingpong_yield.json")
    ap.add_argument("--ranks", default="out/bench/mpi_ranks.json")
    ap.add_argument("--partition", default="out/bench/mpi_partition.json")
    ap.add_argument("--partition-more", default=None,
                    help="a partitioner run to more ranks (once: minutes and GB): its rows beyond --partition join it")
    ap.add_argument("--out", default="out/bench/mpi_model.json")
    ap.add_argument("--img", default="out/bench/img")
    ap.add_argument("--combined", default=None, help="also write every input and the model in one JSON here")
    a = ap.parse_args()
    pp = json.load(open(a.pingpong))
    ppy = json.load(open(a.pingpong_yield)) if os.path.exists(a.pingpong_yield) else pp
    ranks = json.load(open(a.ranks))
    part = json.load(open(a.partition))
    rows = [dict(r, source=a.partition) for r in part["rows"]]
    more = None
    if a.partition_more and os.path.exists(a.partition_more):
        more = json.load(open(a.partition_more))
        if more["nodes_per_rank"] != part["nodes_per_rank"] or more["contact_reach_m"] != part["contact_reach_m"]:
            raise SystemExit("model: %s was made with other settings" % a.partition_more)
        top = max(r["ranks"] for r in rows)
        rows += [dict(r, source=a.partition_more) for r in more["rows"] if r["ranks"] > top]
    alpha, beta = pp["alpha_s_min"], pp["beta_s_per_byte_min"]
    run1 = next(r for r in ranks["runs"] if r["P"] == 1)
    nsPerTet = run1["ranks"][0]["stepSeconds"]["median"] / run1["tets"]
    scenes = [s for s in ("pieces", "body", "mixed") if series(rows, s, "hilbert")]

    exts = {s: {m: extrapolate(rows, s, m) for m in ("hilbert", "slabs")} for s in scenes}
    # The end-of-step reduction is a fixed-order tree (MpiCommunicator::treeReduce).
    proj = project(rows, exts, nsPerTet, alpha, beta, scenes, tree=True)
    # The same with a network 10x slower in latency and bandwidth than this
    # machine's shared memory (an assumption, not a measurement: how much room there is).
    projSlow = project(rows, exts, nsPerTet, 10 * alpha, 10 * beta, scenes)
    projCurve = project(rows, exts, nsPerTet, alpha, beta, scenes, curve=pingpongCurve(pp))
    # As before the tree was built: an allgather summed in rank order (for comparison).
    projTree = project(rows, exts, nsPerTet, alpha, beta, scenes, tree=False)
    nsPerTetMin = run1["ranks"][0]["stepSeconds"]["min"] / run1["tets"]
    val = validate(ranks, os.path.dirname(a.ranks) or ".", nsPerTet, nsPerTetMin, alpha, beta, ppy["alpha_s_min"],
                   ppy["beta_s_per_byte_min"])

    at = lambda pr, P: {k: next(p for p in v if p["P"] == P)["efficiency"] for k, v in pr.items()}
    # Memory: every rank holds the whole world today (Domain.hpp).
    rss = run1["ranks"][0]["maxRssKB"]
    bytesPerNode = 1024.0 * (rss["end"] - rss["afterImport"]) / run1["nodes"]
    nodesPerRank = part["nodes_per_rank"]
    res = {
        "inputs": {"alpha_s": alpha, "beta_s_per_byte": beta, "from": a.pingpong,
                   "alpha_yield_s": ppy["alpha_s_min"], "beta_yield_s_per_byte": ppy["beta_s_per_byte_min"],
                   "ns_per_tet": 1e9 * nsPerTet, "ns_per_tet_from_min_step": 1e9 * nsPerTetMin,
                   "ns_per_tet_from": "P = 1 run: median step seconds / tets (%d tets, 1 thread, contact-free)"
                                      % run1["tets"],
                   "partition": a.partition, "partition_more": a.partition_more if more else None,
                   "nodes_per_rank": nodesPerRank,
                   "partitioner_max_P": max(r["ranks"] for r in rows), "gather_doubles_per_rank": GATHER_DOUBLES},
        "formula": "T(P) = w*imbalance*tets/P + alpha*2*neighbours_max + beta*max(bytes sent, received)_max "
                   "+ 2*log2(P)*(alpha + beta*8*n) (the fixed-order tree reduction); E = T1/T(P), "
                   "T1 = w*tets/P (the mean share, no messages)",
        "extrapolation": exts,
        "efficiency_at": {str(P): at(proj, P) for P in (128, 1024, 5120, 16384)},
        "efficiency_at_pingpong_curve": {str(P): at(projCurve, P) for P in (1024, 5120, 16384)},
        "efficiency_with_allgather": {str(P): at(projTree, P) for P in (1024, 5120, 16384)},
        "efficiency_at_slow_network_10x": {str(P): at(projSlow, P) for P in (1024, 16384)},
        "projection": proj,
        "validation": val,
        "memory": {"bytes_per_node_measured": bytesPerNode,
                   "how": "peak RSS of the P = 1 run after the run minus after import, over its nodes (all of the "
                          "world's per-node and per-tet storage plus the Python mesh copies, per node)",
                   "replicated_GB_per_rank_at": {str(P): bytesPerNode * nodesPerRank * P / 1e9
                                                 for P in (4, 128, 1024, 16384)},
                   "distributed_GB_per_rank": bytesPerNode * nodesPerRank * 1.2 / 1e9,
                   "partition_seconds_per_rank_at_max_P": max(
                       (r["partition_seconds"], r["ranks"]) for r in rows if r["method"] == "hilbert")},
    }
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
    if a.combined:
        with open(a.combined, "w") as f:
            json.dump({"what": "make bench-mpi: doc/parallel_scaling.md, sections Benchmark and Weak-scaling model",
                       "pingpong": pp, "pingpong_yield": ppy, "ranks": ranks, "partition": part,
                       "partition_more": more, "model": res}, f, indent=1)
    plots(proj, rows, a.img, scenes)
    print("model: alpha %.3g s, beta %.3g s/B, %.1f ns/tet" % (alpha, beta, 1e9 * nsPerTet))
    for P, e in res["efficiency_at"].items():
        print("model: E(%s) = %s" % (P, ", ".join("%s %.3f" % kv for kv in e.items())))
    for v in val:
        print("model: P=%d halo counts exact: %s; step model %.2f ms (passive-wait alpha, beta: %.2f ms) vs measured "
              "median %.2f ms (min %.2f), load %.1f"
              % (v["P"], v["halo_counts_exact"], 1e3 * v["step_s_model_max"], 1e3 * v["step_s_model_yield_max"],
                 1e3 * v["step_s_measured_median_max"], 1e3 * v["step_s_measured_min_max"], v["load_average_after"]))
    print("model: wrote", a.out, "and", a.combined or "")


if __name__ == "__main__":
    main()
