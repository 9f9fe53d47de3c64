"""The figures of doc/performance.md and doc/parallel_scaling.md, drawn (PNG)
from the benchmarks' kept JSON, as perf_tables.py prints its tables: no point
on a plot is typed by hand.

    /usr/bin/python3.11 scripts/bench/perf_plots.py roofline OUT.png \
        bench/logs/roofline_2026-11-24.json ELEMENTS.json KERNEL_OPS.json
    /usr/bin/python3.11 scripts/bench/perf_plots.py mpiEfficiency OUT.png bench/logs/mpi.json   (or mpiHalo)

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


# -- MPI at scale (doc/parallel_scaling.md): the weak-scaling model's projection --

MPI_COLOURS = {"pieces": "tab:blue", "body": "tab:red", "mixed": "tab:green"}


def _mpiScenes(proj):
    return [s for s in ("pieces", "body", "mixed") if "%s/hilbert" % s in proj]


def drawMpiEfficiency(proj, out):
    """E(P) of every scene and split (model.projection), the seed's 5,120 cores marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for scene in _mpiScenes(proj):
        for method, ls in (("hilbert", "-"), ("slabs", "--")):
            pts = [p for p in proj["%s/%s" % (scene, method)] if p["P"] != 5120]
            ax.plot([p["P"] for p in pts], [p["efficiency"] for p in pts], ls, color=MPI_COLOURS[scene], marker=".",
                    label="%s, %s" % (scene, method))
    ax.axvline(5120, color="grey", lw=0.8)
    ax.text(5120, 0.05, " seed: 5,120 cores\n (no figure given)", fontsize=8, color="grey")
    ax.set_xscale("log", base=2)
    ax.set_ylim(0, 1.05)
    ax.set_xlabel("ranks P (50,000 nodes each)")
    ax.set_ylabel("weak-scaling efficiency T(1)/T(P)")
    ax.set_title("QDEM weak scaling, model (measured alpha, beta, ns/tet)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def drawMpiHalo(proj, out):
    """Halo over owned and neighbours (maxima over ranks) against P: the
    partitioner's rows as dots, the fits beyond them faint."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.5))
    for scene in _mpiScenes(proj):
        for method, ls in (("hilbert", "-"), ("slabs", "--")):
            pts = proj["%s/%s" % (scene, method)]
            meas = [p for p in pts if p["source"] == "partitioner"]
            fit = [p for p in pts if p["source"] == "fit" or p is meas[-1]]
            for ax, key in ((axs[0], "halo_over_owned_max"), (axs[1], "neighbours_max")):
                ax.plot([p["P"] for p in meas], [p[key] for p in meas], ls, color=MPI_COLOURS[scene], marker="o",
                        ms=3, label="%s, %s" % (scene, method))
                ax.plot([p["P"] for p in fit], [p[key] for p in fit], ls, color=MPI_COLOURS[scene], alpha=0.4)
    for ax, lab in ((axs[0], "halo / owned nodes (max over ranks)"), (axs[1], "neighbours (max over ranks)")):
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("ranks P (50,000 nodes each)")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3, which="both")
    axs[0].legend(fontsize=8)
    fig.suptitle("Partitioner (dots), fits beyond (faint): Hilbert (solid) vs slabs (dashed)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def mpiEfficiency(out, mpiPath):
    """The projected efficiency plot from a kept make bench-mpi JSON (model.projection)."""
    drawMpiEfficiency(json.load(open(mpiPath))["model"]["projection"], out)


def mpiHalo(out, mpiPath):
    """The halo and neighbours plot from a kept make bench-mpi JSON (model.projection)."""
    drawMpiHalo(json.load(open(mpiPath))["model"]["projection"], out)


def main():
    kind, out = sys.argv[1], sys.argv[2]
    if kind == "roofline":
        roofline(out, *sys.argv[3:6])
    elif kind in ("mpiEfficiency", "mpiHalo"):
        globals()[kind](out, sys.argv[3])
    else:
        raise SystemExit("unknown figure %r: roofline, mpiEfficiency, mpiHalo" % kind)


if __name__ == "__main__":
    main()
