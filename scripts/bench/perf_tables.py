"""The tables of doc/performance.md, printed (markdown) from the benchmarks'
JSON, so that the doc is refreshed by pasting, never by retyping figures.

    /usr/bin/python3.11 scripts/bench/perf_tables.py elements  bench/logs/elements_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py roofline  bench/logs/roofline_2026-11-24.json [ELEMENTS.json KERNEL_OPS.json]
    /usr/bin/python3.11 scripts/bench/perf_tables.py cubes27   bench/logs/cubes27_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py shogi     bench/logs/shogi_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py effects   bench/logs/effects_2026-11-28.json \
        [--doc doc/performance.md]   (the table written into the doc between its markers)
    /usr/bin/python3.11 scripts/bench/perf_tables.py ops       bench/logs/kernel_ops_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py timeToSolution bench/logs/time_to_solution_2026-11-28.json

A figure is "median (min-max)" over the runs taken on a quiet machine (no
other process using CPU, load low: MachineLoad.hpp / benchutil.py), with
"n/N" the quiet runs out of all; when no run was quiet the figure is over all
runs and marked "busy"."""
import contextlib
import io
import json
import sys

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


def main():
    kind, path = sys.argv[1], sys.argv[2]
    d = json.load(open(path))
    if kind == "effects" and "--doc" in sys.argv:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            effects(d)
        intoDoc(sys.argv[sys.argv.index("--doc") + 1], buf.getvalue(), path)
    elif kind == "roofline":
        roofline(d, *sys.argv[3:5])
    else:
        {"elements": elements, "cubes27": cubes27, "shogi": shogi, "effects": effects, "ops": ops,
         "spheres": spheres, "glue": glue, "meshSurface": meshSurface,
         "timeToSolution": timeToSolution}[kind](d)


if __name__ == "__main__":
    main()
