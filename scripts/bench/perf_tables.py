"""The tables of doc/performance.md, printed (markdown) from the benchmarks'
JSON, so that the doc is refreshed by pasting, never by retyping figures.

    /usr/bin/python3.11 scripts/bench/perf_tables.py elements  bench/logs/elements_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py roofline  bench/logs/roofline_2026-11-24.json [ELEMENTS.json]
    /usr/bin/python3.11 scripts/bench/perf_tables.py cubes27   bench/logs/cubes27_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py shogi     bench/logs/shogi_2026-11-24.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py effects   bench/logs/effects_2026-11-24.json

A figure is "median (min-max)" over the runs taken on a quiet machine (no
other process using CPU, load low: MachineLoad.hpp / benchutil.py), with
"n/N" the quiet runs out of all; when no run was quiet the figure is over all
runs and marked "busy"."""
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
        print("| law | mode | threads | whole step | element + integration | element only |")
        print("| --- | --- | --- | --- | --- | --- |")
        for c in mesh["cases"]:
            cl, al = c["clean"], c["all"]
            print("| %s | %s | %d | %s | %s | %s |" % (
                LAW.get(c["law"], c["law"]), c["mode"], c["threads"], fig(cl["whole_step"], al["whole_step"]),
                fig(cl["element_integrate"], al["element_integrate"]), fig(cl["element"], al["element"])))


def roofline(d, elementsJson=None):
    print("Roofline program (`scripts/bench/roofline.cpp`, %s, %s): median (min–max) of the quiet runs, "
          "quiet/all.\n" % (d["isa"], d["date"]))
    print("| measure | threads | value |")
    print("| --- | --- | --- |")
    for r in d["results"]:
        print("| %s | %d | %s %s |" % (r["name"], r["threads"], fig(r["clean"], r["all"]), r["unit"]))
    if elementsJson:
        distance(d, json.load(open(elementsJson)))


def best(d, name, threads):
    for r in d["results"]:
        if r["name"] == name and r["threads"] == threads:
            return (r["clean"] or r["all"])["max"] if r["unit"] != "ns" else (r["clean"] or r["all"])["min"]
    return None


def distance(roof, el):
    """Element phase against its floor: flops / peak and bytes / bandwidth per tet."""
    k = roof["kernel_counts"]
    print("\nElement phase against the machine (floors from the counts in `kernel_counts`):\n")
    print("| mesh | law, mode | threads | measured element+integration (min) | flop floor | byte floor | "
          "measured / max(floor) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for mesh in el["meshes"]:
        inL3 = mesh["tets"] < 500000
        for c in mesh["cases"]:
            s = c["clean"]["element_integrate"] or c["all"]["element_integrate"]
            key = ("svk" if c["law"] == "saintVenantKirchhoff" else "snh") + "_" + c["mode"]
            if key not in k:
                continue
            th = c["threads"]
            peak = best(roof, "fma_peak", th)                      # GFLOP/s
            bw = best(roof, "triad_l3" if inL3 else "triad_dram", th)  # GB/s
            flopNs = k[key]["flops_per_tet"] / peak
            byteNs = k["bytes_per_tet"] / bw
            print("| %d | %s %s | %d | %.1f | %.2f | %.2f | %.1f× |" % (
                mesh["tets"], LAW.get(c["law"], c["law"]), c["mode"], th, s["min"], flopNs, byteNs,
                s["min"] / max(flopNs, byteNs)))


def cubes27(d):
    print("27 cubes, %d tets, moving scene (%s), %d threads list; ms per step, median (min–max) of quiet "
          "rounds, quiet/all.\n" % (d["tets"], d["scene"], len(d["threads"])))
    print("| threads | case | amortised step | ordinary step | rebuild step | rebuilds | contacts | ns/tet (amortised) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for th, cases in sorted(d["threads"].items()):
        for name, c in cases.items():
            print("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                th, name, fig(c["clean"]["step_ms"], c["all"]["step_ms"], 2),
                fig(c["clean"]["ordinary_step_ms"], c["all"]["ordinary_step_ms"], 2),
                fig(c["clean"]["rebuild_step_ms"], c["all"]["rebuild_step_ms"], 2),
                c["rebuilds_per_round"], fig(c["clean"]["contact_ms"], c["all"]["contact_ms"], 2),
                fig(c["clean"]["ns_per_tet_step"], c["all"]["ns_per_tet_step"], 1)))
    print("\nTargets (issue 16 target 2, 2 threads):")
    for k, v in d["targets"].items():
        print("- %s: target %s, measured %s" % (k, v["target"], "not measured" if v["measured"] is None
                                                else "%.3g" % v["measured"]))


def shogi(d):
    print("Shogi scenes through `QdemEngine` (%s); ms per step, median (min–max) of quiet rounds.\n" % d["date"])
    print("| scene | pieces | tets | threads | steps | first hit at step | ms per step | s wall per simulated s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, s in d["scenes"].items():
        print("| %s | %d | %d | %d | %d | %s | %s | %s |" % (
            name, s["pieces"], s["tets"], s["threads"], s["steps"], s["first_hit_step"],
            fig(s["clean"]["ms_per_step"], s["all"]["ms_per_step"], 2),
            fig(s["clean"]["wall_s_per_simulated_s"], s["all"]["wall_s_per_simulated_s"], 0)))


def effects(d):
    print("Effects on the 27-cube scene, %d threads, %d steps per variant, %d rounds interleaved (%s); ms per "
          "step, median (min–max) of quiet rounds.\n" % (d["threads"], d["steps"], d["rounds"], d["date"]))
    print("| effect | on | off | zero-valued |")
    print("| --- | --- | --- | --- |")
    for name, e in d["effects"].items():
        cells = [fig(e["clean"].get(v), e["all"].get(v), 2) if e["all"].get(v) else "—"
                 for v in ("on", "off", "zero")]
        print("| %s | %s |" % (name, " | ".join(cells)))


def main():
    kind, path = sys.argv[1], sys.argv[2]
    d = json.load(open(path))
    if kind == "roofline":
        roofline(d, sys.argv[3] if len(sys.argv) > 3 else None)
    else:
        {"elements": elements, "cubes27": cubes27, "shogi": shogi, "effects": effects}[kind](d)


if __name__ == "__main__":
    main()
