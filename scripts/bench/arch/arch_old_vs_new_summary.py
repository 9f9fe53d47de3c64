"""Figures, ratios and verdicts from arch_old_vs_new_run.py's raw JSON.

    /usr/bin/python3.11 scripts/bench/arch/arch_old_vs_new_summary.py RAW.json[,RAW2.json...] OUT.json OUT.md SUBSET [LOAD_LIMIT=2.5]

SUBSET picks the runs the figures are taken over: "load" - the runs whose
1-minute load average read just before was at most LOAD_LIMIT (2 cores,
shared); "quiet" - the runs during which other processes took less than half a
core; "all" - every run.  The other runs are counted as flagged in each row.

Noise band of a figure: the larger relative interquartile range (IQR /
median) of its old runs and of its new runs.  Verdict: "slower" or "faster" when the 95 % interval of the median paired
ratio (new/old of the same round) excludes 1, "within noise" when it holds 1;
with too few pairs for an interval (< 6), the ratio of the medians against
1 +- the noise band."""
import json
import math
import statistics as st
import sys

raw, outJson, outMd, subset = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
limit = float(sys.argv[5]) if len(sys.argv) > 5 else 2.5
# RAW: one raw file or several, comma-separated (sittings one after the
# other); a pair is an old and a new run of the same round of the same sitting.
runsAll = []
# arch_old_vs_new.json itself (raw runs under "sittings") works as RAW too:
# its sittings that have no "not in the summary" note are read.
sittings = []
for path in raw.split(","):
    x = json.load(open(path))
    sittings += [s for s in x["sittings"] if "not in the summary" not in s.get("note", "")] if "sittings" in x else [x]
for i, x in enumerate(sittings):
    for run in x["runs"]:
        runsAll.append(dict(run, round="%d.%s" % (i, run["round"])))
d = {"runs": runsAll}


def figures(bench, r):
    f = {}
    if bench == "elements" and "meshes" in r:
        # bench_elements' present form (Hilbert-ordered meshes, whole step
        # reported): the 27-cube mesh; this harness flags whole processes, so
        # the medians over all runs of the process are read.
        for c in next(m for m in r["meshes"] if m["cubes_per_axis"] == 3)["cases"]:
            short = {"saintVenantKirchhoff": "SVK", "stableNeoHookean": "SNH"}[c["law"]]
            key = "elements %s %s %dth " % (short, c["mode"], c["threads"])
            f[key + "element+integration ns/tet/step"] = c["all"]["element_integrate"]["median"]
            f[key + "element-only ns/tet/step"] = c["all"]["element"]["median"]
            f[key + "whole step ns/tet/step"] = c["all"]["whole_step"]["median"]
    elif bench == "elements":
        for th in ("1", "2"):
            for law, short in (("saintVenantKirchhoff", "SVK"), ("stableNeoHookean", "SNH")):
                for mode in ("viscous", "elastic"):
                    x = r["threads"][th][law][mode]
                    f["elements %s %s %sth element+integration ns/tet/step" % (short, mode, th)] = x["ns_per_tet_step_median"]
                    f["elements %s %s %sth element-only ns/tet/step" % (short, mode, th)] = x["element_ns_per_tet_step_median"]
    elif bench == "cubes27" and r.get("benchmark") == "bench_cubes27":
        # the moving scene (bench_cubes27.py since issue 16): medians of the process's rounds
        for th, cases in r["threads"].items():
            for case, c in cases.items():
                f["cubes27 %s %sth step ms" % (case, th)] = c["all"]["step_ms"]["median"]
            f["cubes27 ours %sth contact ms" % th] = cases["ours"]["all"]["contact_ms"]["median"]
            f["cubes27 ours %sth elements ms" % th] = cases["ours"]["all"]["elements"]["median"]
            if cases["ours"]["all"]["rebuild_step_ms"]:
                f["cubes27 Verlet-rebuild step %sth ms" % th] = cases["ours"]["all"]["rebuild_step_ms"]["median"]
    elif bench == "cubes27":
        for th in ("1", "2"):
            for case in ("ours", "C", "B", "A"):
                f["cubes27 %s %sth step ms" % (case, th)] = r["threads"][th][case]["step_ms"]
            f["cubes27 ours %sth contact ms" % th] = r["threads"][th]["ours"]["contact_ms"]
            f["cubes27 ours %sth elements ms" % th] = r["threads"][th]["ours"]["elements"]
        f["cubes27 Verlet-rebuild step 2th ms"] = r["verlet_rebuild_2_threads"]["rebuild_step_ms"]
    elif bench == "shogi":
        for name, s in r["scenes"].items():
            f["shogi %s 2th step ms" % name] = s["ms_per_step"]
        f["shogi forty sleeping-on all-awake 2th step ms"] = r["sleeping"]["ms_per_step_sleep_on_all_awake"]
        f["shogi forty 39-of-40-asleep 2th step ms"] = r["sleeping"]["ms_per_step_39_asleep"]
    elif bench == "spheres":
        for case in ("near", "far"):
            f["spheres %s whole step (wall) ms" % case] = r[case]["wall_ms_per_step"]
            f["spheres %s QdemEngine ms" % case] = r[case]["qdem_engine_ms_per_step"]
            f["spheres %s coupling ms" % case] = r[case]["coupling_ms_per_step"]
            f["spheres %s YADE-own ms" % case] = r[case]["yade_ms_per_step"]
    return f


def quart(v):
    q = st.quantiles(v, n=4, method="inclusive") if len(v) > 1 else [v[0]] * 3
    return q[0], q[2]


vals = {}   # figure -> build -> [(round, value, flagged)]
for run in d["runs"]:
    if "result" not in run:
        continue
    flagged = {"load": float(run["loadavg_before"][0]) > limit,
               "quiet": run.get("others_cores_during_run", 99) >= 0.5, "all": False}[subset]
    for k, v in figures(run["bench"], run["result"]).items():
        vals.setdefault(k, {"old": [], "new": []})[run["build"]].append((run["round"], v, flagged))

rows = []
for k, b in vals.items():
    row = {"figure": k}
    for tag in ("old", "new"):
        clean = [v for _, v, fl in b[tag] if not fl]
        row[tag] = {"n": len(clean), "n_flagged": sum(fl for _, _, fl in b[tag]),
                    "min": min(clean) if clean else None, "median": st.median(clean) if clean else None,
                    "max": max(clean) if clean else None,
                    "rel_iqr": (lambda q: (q[1] - q[0]) / st.median(clean))(quart(clean)) if clean else None,
                    "all_runs": [v for _, v, _ in b[tag]], "flagged": [fl for _, _, fl in b[tag]]}
    o, n = row["old"], row["new"]
    if o["n"] and n["n"]:
        row["ratio_median"] = n["median"] / o["median"]
        row["ratio_min"] = n["min"] / o["min"]
        old = {r: v for r, v, fl in b["old"] if not fl}
        pairs = [v / old[r] for r, v, fl in b["new"] if not fl and r in old]
        row["paired_ratio_median"] = st.median(pairs) if pairs else None
        row["n_pairs"] = len(pairs)
        # sign test on the pairs: how often the new build was the slower one
        k = sum(x > 1 for x in pairs)
        row["pairs_new_slower"] = k
        m = len(pairs)
        tail = sum(math.comb(m, i) for i in range(0, min(k, m - k) + 1)) / 2 ** m if m else 1.0
        row["sign_test_p"] = min(1.0, 2 * tail)
        band = max(o["rel_iqr"], n["rel_iqr"])
        row["noise_band"] = band
        # distribution-free 95 % interval of the median paired ratio (order
        # statistics k and m-k+1, k the largest with 2 P(Bin(m,1/2) < k) <= 0.05)
        ps = sorted(pairs)
        k = 0
        while k + 1 <= m and 2 * sum(math.comb(m, i) for i in range(k + 1)) / 2 ** m <= 0.05:
            k += 1
        row["paired_ratio_ci95"] = [ps[k - 1], ps[m - k]] if k >= 1 else None
        x = row["ratio_median"]
        if row["paired_ratio_ci95"]:
            lo, hi = row["paired_ratio_ci95"]
            row["verdict"] = "within noise" if lo <= 1 <= hi else ("faster" if hi < 1 else "slower")
        else:
            row["verdict"] = ("within noise" if abs(x - 1) <= band else ("faster" if x < 1 else "slower"))
    rows.append(row)

json.dump({"subset": subset, "load_limit": limit, "rows": rows}, open(outJson, "w"), indent=1)


def key(name):
    """The rows the markdown table shows (the JSON has every figure)."""
    if name.startswith("elements"):
        return "element+integration" in name or ("viscous" in name and "element-only" in name)
    if name.startswith("cubes27"):
        return name.startswith("cubes27 ours") or name == "cubes27 C 2th step ms"
    if name.startswith("spheres"):
        return "wall" in name or "QdemEngine" in name
    return True


def fmt(x, p=3):
    return "-" if x is None else ("%.*f" % (p, x))


with open(outMd, "a") as f:
    f.write("\nRuns: %s.\n\n" % {"load": "1-min load average <= %g before the run" % limit,
                                   "quiet": "other processes took < 0.5 core during the run",
                                   "all": "every run, loaded or not"}[subset])
    f.write("| figure | old min / median (n) | new min / median (n) | new/old median | new/old min | paired median [95 % CI] | new slower in pairs (sign p) | noise band (old/new IQR) | verdict |\n")
    f.write("|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        if not key(r["figure"]):
            continue
        o, n = r["old"], r["new"]
        f.write("| %s | %s / %s (%d%s) | %s / %s (%d%s) | %s | %s | %s | %s | %s | %s |\n" % (
            r["figure"], fmt(o["min"]), fmt(o["median"]), o["n"], ", %d flagged" % o["n_flagged"] if o["n_flagged"] else "",
            fmt(n["min"]), fmt(n["median"]), n["n"], ", %d flagged" % n["n_flagged"] if n["n_flagged"] else "",
            fmt(r.get("ratio_median")), fmt(r.get("ratio_min")),
            fmt(r.get("paired_ratio_median")) + (" [%.3f, %.3f]" % tuple(r["paired_ratio_ci95"]) if r.get("paired_ratio_ci95") else ""),
            "%d/%d (%.2f)" % (r["pairs_new_slower"], r["n_pairs"], r["sign_test_p"]) if r.get("n_pairs") else "-",
            "±%.1f %%" % (100 * r["noise_band"]) if "noise_band" in r else "-", r.get("verdict", "-")))
