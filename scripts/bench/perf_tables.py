"""The tables of measured figures on the user pages (doc/performance.md,
doc/parallel_scaling.md, ...), printed (markdown) from the benchmarks' JSON:
the site prints them at build time (the bench-table directive, which calls
GENERATORS[kind](json, *more json paths)), so no figure is retyped.

    /usr/bin/python3.11 scripts/bench/perf_tables.py elements  bench/logs/elements_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py roofline  bench/logs/roofline_2026-11-24.json [ELEMENTS.json KERNEL_OPS.json]
    /usr/bin/python3.11 scripts/bench/perf_tables.py cubes27   bench/logs/cubes27_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py shogi     bench/logs/shogi_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py effects   bench/logs/effects_2026-11-28.json \
        [--doc doc/performance.md]   (the table written into the doc between its markers)
    /usr/bin/python3.11 scripts/bench/perf_tables.py ops       bench/logs/kernel_ops_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py zoltan    bench/logs/mpi_zoltan.json bench/logs/mpi.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py mpiRanks  bench/logs/mpi.json     (and the other mpi* tables)
    /usr/bin/python3.11 scripts/bench/perf_tables.py timeToSolution bench/logs/time_to_solution_2026-11-28.json

A figure is "median (min-max)" over the runs taken on a quiet machine (no
other process using CPU, load low: MachineLoad.hpp / benchutil.py), with
"n/N" the quiet runs out of all; when no run was quiet the figure is over all
runs and marked "busy"."""
import contextlib
import io
import json
import sys

from page_tables import PAGE_GENERATORS

LAW = {"saintVenantKirchhoff": "SVK", "stableNeoHookean": "SNH (default)"}


def fig(clean, all_, digits=1):
    """'median (min-max) n/N' of the clean runs, or of all runs marked busy."""
    if all_ is None:
        return "not measured"
    s, tag = (clean, "") if clean else (all_, " busy")
    return "%.*f (%.*f–%.*f) %d/%d%s" % (digits, s["median"], digits, s["min"], digits, s["max"],
                                        clean["n"] if clean else 0, all_["n"], tag)


def elements(d):
    print("Built as `qdem.addPiece` builds them (Hilbert order); label %r, %s; ns per tet per step, "
          "median (min–max) of the quiet runs, quiet/all runs." % (d.get("label", ""), d["date"]))
    for mesh in d["meshes"]:
        print("\n%d tets (%d cubes of 6,144), %d nodes, %d steps per run:\n"
              % (mesh["tets"], mesh["cubes_per_axis"] ** 3, mesh["nodes"], mesh["steps"]))
        print("| law | mode | threads | whole step | element + integration | element only | whole step on CPU |")
        print("| --- | --- | --- | --- | --- | --- | --- |")
        for c in mesh["cases"]:
            cl, al = c["clean"], c["all"]
            print("| %s | %s | %d | %s | %s | %s | %s |" % (
                LAW.get(c["law"], c["law"]), c["mode"], c["threads"], fig(cl["whole_step"], al["whole_step"]),
                fig(cl["element_integrate"], al["element_integrate"]), fig(cl["element"], al["element"]),
                fig(cl.get("whole_step_on_cpu"), al.get("whole_step_on_cpu"))))


def roofline(d, elementsJson=None, opsJson=None):
    print("Roofline program (`scripts/bench/roofline.cpp`, %s, %s): median (min–max) of the quiet runs, "
          "quiet/all.  \"On CPU\": the same runs' work over the CPU time their threads held (what a core "
          "delivers while it runs the loop; time-sharing with other processes removed).\n" % (d["isa"], d["date"]))
    print("| measure | threads | wall clock | on CPU |")
    print("| --- | --- | --- | --- |")
    for r in d["results"]:
        print("| %s | %d | %s %s | %s %s |" % (r["name"], r["threads"], fig(r["clean"], r["all"]), r["unit"],
                                            fig(r["on_cpu"]["clean"], r["on_cpu"]["all"]), r["unit"]))
    if elementsJson and opsJson:
        distance(d, json.load(open(elementsJson)), json.load(open(opsJson)))


def ceiling(d, name, threads):
    """The best rate measured (max over quiet runs, else over all, on CPU)."""
    for r in d["results"]:
        if r["name"] == name and r["threads"] == threads:
            return (r["on_cpu"]["clean"] or r["on_cpu"]["all"])["max"]
    return None


def distance(roof, el, ops):
    """Element phase against its floors: flops / peak and bytes / bandwidth per tet."""
    print("\nElement + integration against the machine (flops and bytes per tet from `%s`; ceilings: the best "
          "on-CPU rates above; measured: the minimum over the runs on wall clock (quiet runs if any), and the "
          "median of the whole step on CPU, which bounds element + integration from above):\n" % ops["source"])
    print("| tets | law, mode | threads | flop floor | byte floor | measured (wall, min) | ÷ floor | "
          "whole step on CPU (median) | ÷ floor |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for mesh in el["meshes"]:
        inL3 = mesh["tets"] < 500000
        for c in mesh["cases"]:
            s = c["clean"]["element_integrate"] or c["all"]["element_integrate"]
            cpu = c["clean"].get("whole_step_on_cpu") or c["all"].get("whole_step_on_cpu")
            key = "%s %s" % (c["law"], c["mode"])
            if key not in ops["per_tet"]:
                continue
            th = c["threads"]
            flopNs = ops["per_tet"][key]["flops"] / ceiling(roof, "fma_peak", th)
            byteNs = ops["per_tet"][key]["bytes"] / ceiling(roof, "triad_l3" if inL3 else "triad_dram", th)
            floor = max(flopNs, byteNs)
            print("| %d | %s %s | %d | %.2f | %.2f | %.1f | %.1f× | %s | %s |" % (
                mesh["tets"], LAW.get(c["law"], c["law"]), c["mode"], th, flopNs, byteNs, s["min"], s["min"] / floor,
                "%.1f" % cpu["median"] if cpu else "not measured",
                "%.1f×" % (cpu["median"] / floor) if cpu else "—"))


def ops(d):
    print("| law, mode | FMA | MUL | ADD/SUB | other | elementBatch flops | + scatter, integration | bytes |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for key, k in d["kernel"].items():
        law, mode = key.split()
        p, t = k["per_tet"], d["per_tet"][key]
        print("| %s %s | %.1f | %.1f | %.1f | %.1f | %.0f | %.0f | %.0f |" % (
            LAW.get(law, law), mode, p["fma"], p["mul"], p["add_sub"], p["other"], k["flops_per_tet"],
            t["flops"], t["bytes"]))


def cubes27(d):
    print("%d tets: %s; %s; ms per step, median (min–max) of the quiet rounds, quiet/all rounds; ours amortised "
          "over its Verlet rebuilds, A/B/C fill their cell lists every step.\n" % (d["tets"], d["scene"], d["date"]))
    print("| threads | case | amortised step | ordinary step | rebuild step | window step | costliest rebuild step "
          "/ ordinary (within a run) | rebuilds | contacts | ns/tet (amortised) | ns/tet on CPU |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for th, cases in sorted(d["threads"].items()):
        for name, c in cases.items():
            print("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                th, name, fig(c["clean"]["step_ms"], c["all"]["step_ms"], 2),
                fig(c["clean"]["ordinary_step_ms"], c["all"]["ordinary_step_ms"], 2),
                fig(c["clean"]["rebuild_step_ms"], c["all"]["rebuild_step_ms"], 2),
                fig(c["clean"].get("window_step_ms"), c["all"].get("window_step_ms"), 2),
                fig(c["clean"].get("costliest_rebuild_over_ordinary"), c["all"].get("costliest_rebuild_over_ordinary"),
                    2),
                c["rebuilds_per_round"], fig(c["clean"]["contact_ms"], c["all"]["contact_ms"], 2),
                fig(c["clean"]["ns_per_tet_step"], c["all"]["ns_per_tet_step"], 1),
                fig(c["clean"].get("ns_per_tet_step_on_cpu"), c["all"].get("ns_per_tet_step_on_cpu"), 1)))
    paired = d.get("paired_variant_ratios") or {}
    if paired:
        print("\nVariants of ours against ours, round by round (median (min–max) of the paired ratios):\n")
        print("| threads | variant | amortised step | ordinary step | contacts | elements |")
        print("| --- | --- | --- | --- | --- | --- |")
        for th, byVariant in sorted(paired.items()):
            for name, r in byVariant.items():
                cell = ["%.3f (%.3f–%.3f)" % (r[k]["median"], r[k]["min"], r[k]["max"]) if r.get(k) else "—"
                        for k in ("step_ms", "ordinary_step_ms", "contact_ms", "elements")]
                print("| %s | %s | %s |" % (th, name, " | ".join(cell)))
    print("\nTargets (2 threads):")
    for k, v in d["targets"].items():
        print("- %s: target %s, measured %s" % (k, v["target"], "not measured" if v["measured"] is None
                                                else "%.3g" % v["measured"]))


def shogi(d):
    print("Shogi scenes through `QdemEngine` (%s); ms per step, median (min–max) of quiet rounds.\n" % d["date"])
    print("| scene | pieces | tets | threads | steps | first hits at step | most asleep | ms per step | "
          "s wall per simulated s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, s in d["scenes"].items():
        print("| %s | %d | %d | %d | %d | %s | %s | %s | %s |" % (
            name, s["pieces"], s["tets"], s["threads"], s["steps"], ", ".join(map(str, s["first_hit_step"])),
            max(r.get("most_asleep", 0) for r in s["runs"]),
            fig(s["clean"]["ms_per_step"], s["all"]["ms_per_step"], 2) + " (on CPU %s)"
            % fig(s["clean"].get("ms_per_step_on_cpu"), s["all"].get("ms_per_step_on_cpu"), 2),
            fig(s["clean"]["wall_s_per_simulated_s"], s["all"]["wall_s_per_simulated_s"], 0)))


def spheres(d):
    """The sphere-coupling table (doc/spheres.md) from bench_spheres.py's JSON."""
    print("%d YADE spheres around one QDEM block, %d threads (%s); ms per step over the measured steps.\n"
          % (d["spheres"], d["threads"], d["date"]))
    print("| scene | YADE's own step | sphere coupling | fraction | spheres listed | contacts |")
    print("|---|---|---|---|---|---|")
    for name, label in (("near", "near (settling onto the block)"), ("far", "far (block 10 m above its container)")):
        s = d[name]
        print("| %s | %.2f ms | %.3f ms | **%.1f %%** | %d | %d |" % (
            label, s["yade_ms_per_step"], s["coupling_ms_per_step"], 100 * s["coupling_fraction"],
            s["spheres_listed"], s["sphere_contacts"]))


def glue(d):
    """The Python glue of a step inside YADE (bench_glue.py's JSON, the rows
    of the last glue it timed): per obstacle count, QdemEngine's and PyRunner's
    time per step beside the core's own step, median (min-max) of the runs,
    and the marginal cost of an obstacle against the one-wall scene."""
    current = d["table"][-1]["glue"]  # the last glue given (a comparison names the old one first)
    rows = sorted((r for r in d["table"] if r["glue"] == current), key=lambda r: r["obstacles"])
    print("The glue of one QDEM step inside YADE (%s), %d steps a run, a %d-tet block with walls or facets; "
          "microseconds per step of CPU time, median (min–max) over the runs (quiet runs if any, else all, "
          "marked busy); load: the 1-minute load average during the runs.\n"
          % (d["date"], d["steps"], d["runs"][0]["tets"]))
    print("| obstacles | glue µs per step | core's own step, µs | each obstacle beyond the first, µs | load |")
    print("| --- | --- | --- | --- | --- |")
    pick = [r["glue_us"] if r["quietRuns"] else r["glue_us_all"] for r in rows]
    for r, g in zip(rows, pick):
        extra = ("%.1f" % ((g["median"] - pick[0]["median"]) / (r["obstacles"] - rows[0]["obstacles"]))
                 if r["obstacles"] > rows[0]["obstacles"] else "—")
        print("| %d | %.0f (%.0f–%.0f)%s | %.0f | %s | %.1f–%.1f |" % (
            r["obstacles"], g["median"], g["min"], g["max"], "" if r["quietRuns"] else " busy",
            r["core_us"]["median"], extra, r["load1"]["min"], r["load1"]["max"]))


def meshSurface(d):
    """The meshSurface quality table (doc/meshes.md) from
    bench_mesh_surface.py's JSON."""
    print("`qdem.meshSurface` on generated surfaces, one thread (%s); step factor: the median element's "
          "smallest height over the smallest; time on the shared machine (load average beside it).\n"
          % d.get("date", "date not recorded"))
    print("| surface | cellSize | tets | meshings | short creases smoothed | step factor | volume kept | "
          "time [s] | load |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in d["rows"]:
        print("| %s | %s | %d | %s | %s | %.2f | %.2f %% | %.1f | %s |" % (
            r["case"], "%.3g" % r["cellSize"] if "cellSize" in r else "search", r["tets"], r.get("passes", "-"),
            r.get("shortFeatures", "-"), r["stepFactor"], 100 * r["volumeKept"], r["seconds"],
            "%.1f" % r["load1"] if "load1" in r else "-"))


def ratio(r):
    """'median (min-max)' of paired per-round ratios, or a dash."""
    return "%.2f (%.2f–%.2f)" % (r["median"], r["min"], r["max"]) if r else "—"


def effects(d):
    """The effects table: QDEM's own share of the step (the core's phase
    timers) and the step on CPU, judged on the paired ratios of the
    interleaved rounds and on minima (effects.json from bench_effects.py)."""
    print("Effects on the 27-cube scene (%d tets), %d threads, %d steps per variant, %d rounds interleaved (%s). "
          "QDEM's share: the core's phase timers summed over the steps (wall clock); on CPU: the process's CPU "
          "time over the 2 threads (in this bare core world all QDEM's but the Python call). Ratios: median "
          "(min–max) over the rounds of the per-round ratio to \"off\" (each round runs every variant back to "
          "back); ms per step: the minimum over all rounds.\n" % (d["tets"], d["threads"], d["steps"], d["rounds"],
                                                                  d["date"]))
    print("| effect | on ÷ off, on CPU | zero ÷ off, on CPU | on ÷ off, QDEM's share | zero ÷ off, QDEM's share | "
          "ms per step on CPU, min: on / off / zero | QDEM's share, min: on / off / zero | whole step, min |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")

    def mins(group):
        return " / ".join("%.2f" % group["all"][v]["min"] if group["all"].get(v) else "—"
                          for v in ("on", "off", "zero"))

    for name, e in d["effects"].items():
        p = e["paired"]
        print("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
            name, ratio(p["on_over_off"].get("cpu")), ratio(p["zero_over_off"].get("cpu")),
            ratio(p["on_over_off"]["qdem"]), ratio(p["zero_over_off"]["qdem"]),
            mins(e.get("on_cpu", {"all": {}})), mins(e["qdem"]), mins({"all": e["all"]})))


# -- MPI at scale (doc/parallel_scaling.md) and under yade.mpy (doc/parallel.md) --

SCENE_ORDER = ("pieces", "body", "mixed")
ZOLTAN_METHODS = ("hilbert", "hilbert-split", "zoltan-hsfc", "zoltan-hsfc-whole", "zoltan-rcb")
SPLIT = {"hilbert": "Hilbert", "slabs": "slabs"}


def sig2(x):
    """Two significant figures, trailing zero kept (1.0, 0.52, 16)."""
    return "%.0f" % x if abs(x) >= 10 else "%.1f" % x if abs(x) >= 1 else "%.2f" % x


def thousands(n):
    """16384 -> '16,384'."""
    return "{:,}".format(int(n))


def stepOverWork(row, alpha, beta, w):
    """The modelled step of the worst rank over the mean share's work
    (doc/parallel_scaling.md, "The formula", without the allgather, which is
    the same for every method): (w imbalance tets/P + alpha 2 neighbours_max
    + beta bytes_max) / (w tets/P)."""
    share = w * row["tets"] / row["ranks"]
    bytesMax = max(row["bytes_sent_per_step_max"], row["bytes_received_per_step_max"])
    return (share * row["imbalance"] + alpha * 2 * row["neighbours_max"] + beta * bytesMax) / share


def _modelInputs(mpiJson):
    inp = json.load(open(mpiJson))["model"]["inputs"]
    return inp["alpha_s"], inp["beta_s_per_byte"], inp["ns_per_tet"] * 1e-9


def _zoltanRows(d, ranks):
    rows = [r for r in d["rows"] if r["ranks"] == ranks]
    order = {(s, m): i for i, (s, m) in enumerate((s, m) for s in SCENE_ORDER for m in ZOLTAN_METHODS)}
    return sorted(rows, key=lambda r: order.get((r["scene"], r["method"]), len(order)))


def zoltan(d, mpiJson):
    """Our split against Zoltan's (mpi_zoltan.json) at the largest P and at
    P = 16; step / work with alpha, beta, w of mpi.json's model.inputs, and
    again with alpha and beta ten times larger."""
    alpha, beta, w = _modelInputs(mpiJson)
    top = max(r["ranks"] for r in d["rows"])
    for ranks in (top, 16):
        print("P = %d:\n" % ranks)
        print("| scene | method | imbalance | halo/owned mean / max | neighbours mean / max | bytes/step max (KB) "
              "| pieces split | partition (s) | step / work | same, 10× slower network |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for r in _zoltanRows(d, ranks):
            print("| %s | %s | %.4f | %.3f / %.3f | %.1f / %d | %.0f | %d | %.2f | %.3f | %.3f |" % (
                r["scene"], r["method"], r["imbalance"], r["halo_over_owned_mean"], r["halo_over_owned_max"],
                r["neighbours_mean"], r["neighbours_max"],
                max(r["bytes_sent_per_step_max"], r["bytes_received_per_step_max"]) / 1000, r["pieces_split"],
                r["partition_seconds"], stepOverWork(r, alpha, beta, w),
                stepOverWork(r, 10 * alpha, 10 * beta, w)))
        print()


def zoltanByP(d):
    """Imbalance and maximum halo over owned by P, ours against Zoltan's
    HSFC and RCB (mpi_zoltan.json)."""
    methods = ("hilbert", "zoltan-hsfc", "zoltan-rcb")
    ranks = sorted(set(r["ranks"] for r in d["rows"]))
    at = {(r["scene"], r["method"], r["ranks"]): r for r in d["rows"]}
    for key, title, digits in (("imbalance", "Imbalance", 3), ("halo_over_owned_max", "Halo over owned, maximum "
                                                                "over ranks", 3)):
        print("%s by P (%s):\n" % (title, " / ".join(methods)))
        print("| scene | P = %s |" % " | ".join(str(p) for p in ranks))
        print("|---|%s" % ("---|" * len(ranks)))
        for s in SCENE_ORDER:
            print("| %s | %s |" % (s, " | ".join(" / ".join("%.*f" % (digits, at[s, m, p][key]) for m in methods)
                                                for p in ranks)))
        print()


def zoltanSlowNetwork(d, mpiJson):
    """Step / work at the largest P with alpha and beta ten times those of
    mpi.json (an assumed cluster network, not a measurement)."""
    alpha, beta, w = _modelInputs(mpiJson)
    top = max(r["ranks"] for r in d["rows"])
    methods = ("hilbert", "hilbert-split", "zoltan-rcb", "zoltan-hsfc")
    at = {(r["scene"], r["method"]): r for r in d["rows"] if r["ranks"] == top}
    print("| scene | %s |" % " | ".join("`%s`" % m for m in methods))
    print("|---|%s" % ("---|" * len(methods)))
    for s, label in (("pieces", "heap"), ("mixed", "mixed"), ("body", "body")):
        print("| %s | %s |" % (label, " | ".join("%.2f" % stepOverWork(at[s, m], 10 * alpha, 10 * beta, w)
                                                for m in methods)))


def mpiPingpong(d):
    """The ping-pong fits t(m) = alpha + beta m (mpi.json: pingpong, pingpong_yield)."""
    p, y = d["pingpong"], d["pingpong_yield"]
    rows = [("busy polling, fit on the minima (**model input**)", p["alpha_s_min"], p["beta_s_per_byte_min"],
             "`mpi.json: pingpong.alpha_s_min, beta_s_per_byte_min`", True),
            ("busy polling, fit on the medians", p["alpha_s_median"], p["beta_s_per_byte_median"],
             "`pingpong.*_median`", False),
            ("messages ≤ 1 KB only (mean) / ≥ 64 KB only (slope)", p["alpha_s_small_messages_min"],
             p["beta_s_per_byte_large_messages_min"],
             "`pingpong.alpha_s_small_messages_min`, `beta_s_per_byte_large_messages_min`", False),
            ("passive waits (`OMPI_MCA_mpi_yield_when_idle=1`), minima", y["alpha_s_min"], y["beta_s_per_byte_min"],
             "`pingpong_yield.*_min`", False)]
    print("| | alpha | beta | bandwidth 1/beta | source |")
    print("|---|---|---|---|---|")
    for label, a, b, src, bold in rows:
        cells = ["%.2f µs" % (a * 1e6), "%.2e s/B" % b, "%.1f GB/s" % (1e-9 / b)]
        if bold:
            cells = ["**%s**" % c for c in cells]
        print("| %s | %s | %s |" % (label, " | ".join(cells), src))


def mpiRanks(d):
    """The contact-free scene on P ranks, rank by rank, then run by run
    (mpi.json: ranks.runs); times in ms."""
    print("| P | rank | owned nodes | owned tets | ghosts | neighbours | bytes sent/step | messages/step "
          "| step median | step min | elements median | exchange median | exchange min |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for run in d["ranks"]["runs"]:
        for r in run["ranks"]:
            print("| %d | %d | %d | %d | %d | %s | %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f |" % (
                run["P"], r["rank"], r["ownedNodes"], r["ownedTets"], r["ghosts"],
                ",".join(map(str, r["neighbours"])) or "-", r["stepBytes"], r["stepMessages"],
                1e3 * r["stepSeconds"]["median"], 1e3 * r["stepSeconds"]["min"],
                1e3 * r["phaseSeconds"]["elements"]["median"], 1e3 * r["exchangeSeconds"]["median"],
                1e3 * r["exchangeSeconds"]["min"]))
    print("\n| P | imbalance (max/mean owned tets) | load average before → after | max \\|Δx\\| vs P = 1 after %d "
          "steps |" % (d["ranks"]["runs"][0]["warmupSteps"] + d["ranks"]["runs"][0]["timedSteps"]))
    print("|---|---|---|---|")
    for run in d["ranks"]["runs"]:
        dx = run["maxAbsDxVsP1"]
        print("| %d | %.6g | %.2f → %.2f | %s |" % (run["P"], run["ranks"][0]["imbalance"],
                                                   run["loadAverageBefore"][0], run["loadAverageAfter"][0],
                                                   "%.1e m" % dx if dx else "0"))


def mpiInputs(d):
    """What the weak-scaling model measures and what it models (mpi.json: model.inputs)."""
    i = d["model"]["inputs"]
    print("| input | how | value | source |")
    print("|---|---|---|---|")
    print("| alpha, beta | ping-pong (busy polling, minima) | %.2f µs, %.2e s/B | `mpi.json: model.inputs` |"
          % (i["alpha_s"] * 1e6, i["beta_s_per_byte"]))
    print("| work per tet `w` | P = 1 run: median step / tets (everything in the step: elements, integration, "
          "obstacles) | %.1f ns/tet (%.1f from the fastest step) | `model.inputs.ns_per_tet`, "
          "`ns_per_tet_from_min_step` |" % (i["ns_per_tet"], i["ns_per_tet_from_min_step"]))
    top = max(r["ranks"] for r in d["partition"]["rows"])
    more = sorted(set(r["ranks"] for r in d["partition_more"]["rows"]) - set(r["ranks"] for r in
                                                                            d["partition"]["rows"]))
    print("| owned tets, imbalance, halo, neighbours, bytes per rank | the real partitioner (`pkg/parallel`) on "
          "synthetic scenes of P × %s nodes, P = 1..%d in `make bench-mpi`, %s from the one-off run | | "
          "`mpi.json: partition.rows`, `mpi_partition_512.json: rows` |"
          % (thousands(i["nodes_per_rank"]), top, " and ".join(map(str, more))))
    print("| same, P > %d | fits to the partitioner's rows (below) | | `model.extrapolation` |"
          % i["partitioner_max_P"])
    print("| times | the formula below | | `model.projection` |")


def _efficiencyTable(at, scenes=SCENE_ORDER, bold=()):
    ps = sorted(at, key=int)
    print("| scene / split | P = %s |" % " | ".join("**%s**" % thousands(p) if p in bold else thousands(p) for p in ps))
    print("|---|%s" % ("---|" * len(ps)))
    for s in scenes:
        for m in ("hilbert", "slabs"):
            print("| %s, %s | %s |" % (s, SPLIT[m], " | ".join("%.3f" % at[p]["%s/%s" % (s, m)] for p in ps)))


def mpiEfficiency(d):
    """Projected weak-scaling efficiency E(P) (mpi.json: model.efficiency_at)."""
    _efficiencyTable(d["model"]["efficiency_at"], bold=("16384",))


def mpiProjection(d):
    """The step at the largest projected P split into its terms (model.projection)."""
    rows = (("pieces", "hilbert"), ("body", "hilbert"), ("body", "slabs"))
    last = {k: v[-1] for k, v in d["model"]["projection"].items()}
    print("At P = %s, times in ms:\n" % thousands(last["body/hilbert"]["P"]))
    print("| | halo/owned (max) | neighbours (max) | bytes (max) | work | halo exchange | allgather | step |")
    print("|---|---|---|---|---|---|---|---|")
    for s, m in rows:
        q = last["%s/%s" % (s, m)]
        print("| %s, %s | %s | %.0f | %s MB | %.2f | %.2f | %.2f | %.2f |" % (
            s, SPLIT[m], sig2(q["halo_over_owned_max"]), q["neighbours_max"], sig2(q["bytes_max"] / 1e6),
            1e3 * q["work_s"], 1e3 * q["halo_s"], 1e3 * q["collective_s"], 1e3 * q["step_s"]))


def _hilbertSlabs(at):
    print("| | Hilbert | slabs |")
    print("|---|---|---|")
    for s in ("pieces", "body"):
        print("| %s | %.3f | %.3f |" % (s, at["%s/hilbert" % s], at["%s/slabs" % s]))


def mpiPingpongCurve(d):
    """E at 16,384 ranks with each rank's halo costed by the measured
    ping-pong curve (model.efficiency_at_pingpong_curve)."""
    _hilbertSlabs(d["model"]["efficiency_at_pingpong_curve"]["16384"])


def mpiRerun(d):
    """E at 16,384 ranks from a second run of make bench-mpi (mpi_rerun.json: model.efficiency_at)."""
    _hilbertSlabs(d["model"]["efficiency_at"]["16384"])


def _signedPercent(x):
    return ("%+.0f %%" % (100 * x)).replace("-", "−")


def mpiExtrapolation(d):
    """The fits' check: fitted on the partitioner's rows to P = 128, their
    relative error at the P it also reached (model.extrapolation[*][*].check_on_overlap)."""
    ex = d["model"]["extrapolation"]
    keys = ("halo_over_owned_max", "bytes_max", "neighbours_max")
    ps = sorted(ex["pieces"]["hilbert"]["check_on_overlap"]["bytes_max"]["predicted_vs_partitioner"], key=int)
    print("| | %s |" % " | ".join("%s, %s" % (k, " / ".join(ps)) for k in
                                   ("halo/owned max", "bytes max", "neighbours max")))
    print("|---|---|---|---|")
    for m in ("hilbert", "slabs"):
        for s in SCENE_ORDER:
            c = ex[s][m]["check_on_overlap"]
            fitted = c["bytes_max"]["fitted_on_P"]
            print("| %s, %s (fit on %d..%d) | %s |" % (s, SPLIT[m], fitted[0], fitted[-1], " | ".join(
                " / ".join(_signedPercent(c[k]["predicted_vs_partitioner"][p]["relative_error"]) for p in ps)
                for k in keys)))


def mpiValidation(d):
    """Modelled against measured step times of the slowest rank, P = 2..4 (model.validation), in ms."""
    print("| P | model, w from the P = 1 median | model, w from the P = 1 minimum | measured, slowest rank, median "
          "| measured, minimum |")
    print("|---|---|---|---|---|")
    for v in d["model"]["validation"]:
        print("| %d | %.2f | %.2f | %.2f | %.2f |" % (v["P"], 1e3 * v["step_s_model_max"],
                                                    1e3 * v["step_s_model_from_min_max"],
                                                    1e3 * v["step_s_measured_median_max"],
                                                    1e3 * v["step_s_measured_min_max"]))


def mpiMemory(d):
    """Memory per rank with the world replicated on every rank
    (model.memory.replicated_GB_per_rank_at)."""
    print("| P | memory per rank |")
    print("|---|---|")
    for p, gb in sorted(d["model"]["memory"]["replicated_GB_per_rank_at"].items(), key=lambda kv: int(kv[0])):
        print("| %s | %s |" % (thousands(p), "%s TB" % sig2(gb / 1000) if gb >= 1000 else "%s GB" % sig2(gb)))


def mpiMpy(d):
    """QDEM under yade.mpy against serial runs (mpi_mpy.json from scripts/mpi/mpy_vs_serial.py)."""
    print("| scene (under mpy, %s steps) | P | max \\|Δx\\| / largest displacement | sphere states / their largest "
          "value | floor force | QDEM energy |" % thousands(d["drop"]["mpy3ranks"]["steps"]))
    print("|---|---|---|---|---|---|")
    for name, label in (("drop", "%d spheres dropped on a block"), ("clump", "a clump thrown along a slab")):
        s = d[name]
        if "%d" in label:
            label %= sum(len(o) for o in s["mpy3ranks"]["owners"])
        for i, (key, p) in enumerate((("mpy3ranks", "3"), ("mpy4ranks", "4"), ("serial1vs2threads",
                                                                              "serial, 1 vs 2 threads"))):
            v = s[key].get("vsSerial", s[key])
            force = "%.1e" % v["floorForce"] + (" of %.0f N" % s["floorForceMax"] if i == 0 else "")
            print("| %s | %s | %.1e | %.1e | %s | %.1e |" % (label if i == 0 else "", p, v["dxOverDisp"],
                                                            v["sphereStates"], force, v["energy"]))
def duration(seconds):
    """A wall time for people: s, min or h."""
    if seconds is None:
        return "—"
    if seconds < 120:
        return "%.0f s" % seconds
    if seconds < 7200:
        return "%.0f min" % (seconds / 60)
    return "%.1f h" % (seconds / 3600)


def timeToSolution(d):
    """The time-to-solution table (bench_time_to_solution.py's JSON): per
    scene and scale, wall s per simulated s with each lever (median of the
    interleaved rounds, the 1-minute load average beside it) and the whole
    run's wall time, projected; then the whole runs, measured or projected."""
    levers = list(d["levers"])
    print("The seed's shogi scenes, Table 1's material, implicit viscosity, %d threads (%s). **Measured**: wall "
          "(CPU) seconds per simulated second over a short window, median of %s interleaved rounds, each lever "
          "over the same steps; CG: iterations of the viscous solve per step. **Projected**: the whole run's wall "
          "time, that rate times the scene's simulated time to its end (at real size; the forty-piece line also "
          "times 3 pieces awake in the 766× runs over those awake at the front). Load: 1-minute load average "
          "during the rounds, min–median (2 cores, shared).\n"
          % (d["threads"], d["date"], next(iter(d["scenes"].values()))["rounds"]))
    print("| scene | scale | pieces (awake) | wall (CPU) s per simulated s: %s | CPU, %s ÷ %s | CG its per step: %s | "
          "projected whole run (%s) | load |" % (" / ".join(levers), levers[0], levers[-1], " / ".join(levers),
                                                 levers[-1]))
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")

    def med(e, lever, key):
        s = e["levers"].get(lever, {}).get("summary")
        return s[key]["median"] if s and s.get(key) else None

    def g(v, digits=3):
        """Three significant digits, thousands separated: 45,100, 18.3, 0.857."""
        if v is None:
            return "—"
        r = float("%.*g" % (digits, v))
        return "{:,.0f}".format(r) if abs(r) >= 1000 else "%.*g" % (digits, r)

    def ratio(e):
        old, new = med(e, levers[0], "cpu_s_per_simulated_s"), med(e, levers[-1], "cpu_s_per_simulated_s")
        return "%.2f" % (old / new) if old and new else "—"

    for name, e in d["scenes"].items():
        if e.get("status") == "failed":
            print("| %s | %s | %d | not measured: the core stopped the run (StabilityError, `error` in the JSON) "
                  "| — | — | — | — |" % (e.get("name", e["scene"]), "real size" if e["scale"] == 1 else
                                         "%g×" % e["scale"], e["pieces"]))
            continue
        rates = " / ".join("%s (%s)" % (g(med(e, v, "wall_s_per_simulated_s")), g(med(e, v, "cpu_s_per_simulated_s")))
                           for v in levers)
        cg = " / ".join(g(med(e, v, "cg_iterations_per_step")) for v in levers)
        p = e["projected_full_run"]
        load = "%.1f–%.1f" % (e["load1"]["min"], e["load1"]["median"]) if e.get("load1") else "—"
        print("| %s | %s | %d (%s) | %s | %s | %s | %s (CPU %s) for %.3g s | %s |" % (
            e.get("name", e["scene"]), "real size" if e["scale"] == 1 else "%g×" % e["scale"], e["pieces"],
            g(e["pieces_awake"]), rates, ratio(e), cg, duration(p["wall_s"]), duration(p.get("cpu_s")),
            p["simulated_s"], load))
    print("\nWhole runs at real size on the same machine:\n")
    print("| run | wall time (CPU time) | status |")
    print("| --- | --- | --- |")
    for name, r in d["full_runs"].items():
        if r["wall_s"] is not None:
            print("| %s | **%s** (CPU %s) | measured, %s, %s threads (`%s`) |" % (
                name, duration(r["wall_s"]), duration(r.get("cpu_s")), r.get("ended") or "ended", r.get("threads"),
                r.get("log", "")))
        else:
            print("| %s | %s (CPU %s) | not run; projected |" % (name, duration(r.get("projected_wall_s")),
                                                                 duration(r.get("projected_cpu_s"))))


BEGIN, END = "<!-- perf_tables.py effects: begin -->", "<!-- perf_tables.py effects: end -->"


def intoDoc(doc, table, source):
    """Put `table` between the markers in `doc` (a Markdown file), naming
    the JSON it came from; the rest of the file is left as it is."""
    text = open(doc).read()
    if BEGIN not in text or END not in text:
        sys.exit("perf_tables: %s has no %s ... %s markers" % (doc, BEGIN, END))
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(doc, "w") as f:
        f.write("%s%s\n%s\nFrom `%s`.\n%s%s" % (head, BEGIN, table.rstrip("\n"), source, END, tail))


# Every table this file prints: generator(json, *more json paths).
GENERATORS = {f.__name__: f for f in (
    elements, roofline, cubes27, shogi, effects, ops, spheres, glue, meshSurface, zoltan, zoltanByP,
    zoltanSlowNetwork, mpiPingpong, mpiRanks, mpiInputs, mpiEfficiency, mpiProjection, mpiPingpongCurve, mpiRerun,
    mpiExtrapolation, mpiValidation, mpiMemory, mpiMpy, timeToSolution)}
GENERATORS.update(PAGE_GENERATORS)  # doc/parallel.md's and doc/shogi.md's (page_tables.py)


def main():
    kind, path, more = sys.argv[1], sys.argv[2], [a for a in sys.argv[3:] if not a.startswith("--")]
    d = json.load(open(path))
    if kind == "effects" and "--doc" in sys.argv:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            effects(d)
        intoDoc(sys.argv[sys.argv.index("--doc") + 1], buf.getvalue(), path)
    elif kind in GENERATORS:
        GENERATORS[kind](d, *more)
    else:
        sys.exit("perf_tables: no table %r; one of %s" % (kind, ", ".join(sorted(GENERATORS))))


if __name__ == "__main__":
    main()
