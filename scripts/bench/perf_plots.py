"""The figures of doc/performance.md, drawn (PNG) from the benchmarks' kept
JSON, as perf_tables.py prints its tables: no point on a plot is typed by hand.

    /usr/bin/python3.11 scripts/bench/perf_plots.py roofline OUT.png \
        bench/logs/roofline_2026-11-24.json ELEMENTS.json KERNEL_OPS.json

roofline: the machine's ceilings measured by scripts/bench/roofline.cpp (the
best on-CPU FMA rate, the best triad bandwidths from L3 and DRAM) against
the element + integration pass of each law and mode: its arithmetic
intensity is the flops over the bytes per tet counted from the compiled
kernel (scripts/bench/kernel_ops.py), its rate those flops over the fastest
measured ns per tet (bench_elements; either its `make bench` form with
`meshes`, or the old-against-new form of compare_elements.py with `cases`,
whose new build is taken).  Williams, Waterman & Patterson, "Roofline: an
insightful visual performance model for multicore architectures", CACM 52(4),
2009: attainable GFLOP/s = min(peak, intensity × bandwidth)."""
import json
import sys

from perf_tables import LAW, ceiling

# A mesh of fewer tets than this fits the 32 MB L3 with its nodes (128 B/tet).
L3_TETS = 500000


def _elementTimes(el):
    """(tets, law, mode, threads) -> fastest ns per tet of element + integration."""
    out = {}
    if "meshes" in el:
        for mesh in el["meshes"]:
            for c in mesh["cases"]:
                s = c["clean"]["element_integrate"] or c["all"]["element_integrate"]
                if s:
                    out[(mesh["tets"], c["law"], c["mode"], c["threads"])] = s["min"]
    else:
        for c in el["cases"]:
            out[(c["tets"], c["law"], c["mode"], c["threads"])] = c["element_integrate"]["new_min"]
    return out


def roofline(out, roofPath, elementsPath, opsPath):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    roof, el, ops = (json.load(open(p)) for p in (roofPath, elementsPath, opsPath))
    fig, ax = plt.subplots(figsize=(7.5, 5.0), dpi=110)
    ai = np.logspace(-2, 2, 200)
    colours = {1: "tab:blue", 2: "tab:red"}
    for th in (1, 2):
        peak = ceiling(roof, "fma_peak", th)
        if peak is None:
            continue
        for name, style, label in (("triad_l3", "-", "L3"), ("triad_dram", "--", "DRAM")):
            bw = ceiling(roof, name, th)
            if bw is not None:
                ax.plot(ai, np.minimum(peak, ai * bw), style, color=colours[th], lw=1.2,
                        label="%d thread%s: %.0f GFLOP/s, %s %.0f GB/s" % (th, "s" if th > 1 else "", peak, label, bw))
    markers = {"elastic": "o", "viscous": "s"}
    fills = {"saintVenantKirchhoff": "none", "stableNeoHookean": "full"}
    for (tets, law, mode, th), ns in sorted(_elementTimes(el).items()):
        key = "%s %s" % (law, mode)
        if key not in ops["per_tet"]:
            continue
        flops, byts = ops["per_tet"][key]["flops"], ops["per_tet"][key]["bytes"]
        c = colours.get(th, "k")
        ax.plot(flops / byts, flops / ns, markers.get(mode, "^"), ms=7 if tets < L3_TETS else 5,
                color=c, mfc=c if fills.get(law) == "full" else "none", mew=1.4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(0.1, 20)
    ax.set_ylim(1, 250)
    ax.set_xlabel("arithmetic intensity (flop per byte of memory traffic)")
    ax.set_ylabel("GFLOP/s")
    ax.set_title("Element + integration pass against the roofline\n%s, roofline %s" % (roof["isa"], roof["date"][:10]),
                 fontsize=9)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    for law, fill in fills.items():
        for mode, m in markers.items():
            ax.plot([], [], m, color="0.3", mfc="0.3" if fill == "full" else "none", mew=1.4,
                    label="%s, %s" % (LAW.get(law, law), mode))
    ax.legend(fontsize=7, loc="lower right")
    ax.text(0.02, 0.97, "colour: threads; large marker: %s-tet mesh in L3, small: larger mesh from DRAM\n"
            "(%s; flops and bytes per tet: %s)" % ("{:,}".format(min(k[0] for k in _elementTimes(el))),
                                                   elementsPath.split("/")[-1], opsPath.split("/")[-1]),
            transform=ax.transAxes, fontsize=6.5, va="top")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def main():
    kind, out = sys.argv[1], sys.argv[2]
    if kind == "roofline":
        roofline(out, *sys.argv[3:6])
    else:
        raise SystemExit("unknown figure %r: roofline" % kind)


if __name__ == "__main__":
    main()
