"""What accuracy costs in time: every problem with a known answer, every
accuracy knob, error and wall time measured in the same run.

    make accuracy          # full study (3-5 min on one thread): out/accuracy/, doc/accuracy.md, doc/img/accuracy_*.png
    make bench             # runs this with --short (10-20 s): out/accuracy/ only

Usage: run_accuracy.py [--short] [--out DIR] [--no-doc] [--only PROBLEM ...]
Runs on one thread (the cost of threads is in doc/performance.md; threads never
change a result, tests/python/test_threads.py)."""
import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import acclib  # noqa: E402
import bouncing_block  # noqa: E402
import cantilever  # noqa: E402
import hertz_spheres  # noqa: E402
import pwave_bar  # noqa: E402
import sliding_block  # noqa: E402

# name -> (module, run function, cases function, title, error description, negligible |error|)
PROBLEMS = {
    "cantilever": (cantilever, cantilever.run, cantilever.cases, cantilever.TITLE, cantilever.ERROR, 0.01),
    "pwave": (pwave_bar, pwave_bar.run, pwave_bar.cases, pwave_bar.TITLE, pwave_bar.ERROR, 0.0005),
    "hertz": (hertz_spheres, hertz_spheres.run, hertz_spheres.cases, hertz_spheres.TITLE, hertz_spheres.ERROR,
              0.01),
    "sliding": (sliding_block, sliding_block.run, sliding_block.cases, sliding_block.TITLE, sliding_block.ERROR,
                0.005),
    "stick": (sliding_block, sliding_block.runStick, sliding_block.stickCases, sliding_block.STICK_TITLE,
              sliding_block.STICK_ERROR, 1e-5),
    "bouncing": (bouncing_block, bouncing_block.run, bouncing_block.cases, bouncing_block.TITLE,
                 bouncing_block.ERROR, 0.0005),
}


def isDefault(mod, knob, label):
    d = getattr(mod, "DEFAULTS", {}).get(knob)
    return d is not None and label.startswith(d)


def bestLevel(rows, tol):
    """Cheapest level whose |error| is within 10 % (plus a negligible amount
    `tol`) of the smallest |error| of its knob sweep; the default when it
    qualifies and costs within 15 % (timing noise) of that cheapest level."""
    emin = min(abs(r["error"]) for r in rows)
    ok = [r for r in rows if abs(r["error"]) <= 1.1 * emin + tol]
    cheapest = min(ok, key=lambda r: r["wall"])
    for r in ok:
        if r["default"] and r["wall"] <= 1.15 * cheapest["wall"]:
            return r["label"]
    return cheapest["label"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--short", action="store_true", help="short form for make bench (10-20 s)")
    ap.add_argument("--out", default="out/accuracy")
    ap.add_argument("--no-doc", action="store_true", help="do not regenerate doc/accuracy.md (full run only)")
    ap.add_argument("--only", nargs="*", help="run only these problems (%s)" % ", ".join(PROBLEMS))
    a = ap.parse_args(argv)
    acclib.oneThread()
    os.makedirs(a.out, exist_ok=True)
    names = [n for n in PROBLEMS if not a.only or n in a.only]
    plan = [(n, knob, label, kw) for n in names for knob, label, kw in PROBLEMS[n][2](a.short)]
    print("accuracy: %d runs (%s form), one thread" % (len(plan), "short" if a.short else "full"), flush=True)
    t0 = time.time()
    results = {n: dict(title=PROBLEMS[n][3], error=PROBLEMS[n][4], doc=(PROBLEMS[n][0].__doc__ or "").strip(),
                       rows=[]) for n in names}
    for i, (n, knob, label, kw) in enumerate(plan, 1):
        mod, run = PROBLEMS[n][0], PROBLEMS[n][1]
        t = time.time()
        r = run(**kw)
        r.update(knob=knob, label=label, kwargs=kw, default=isDefault(mod, knob, label), total=time.time() - t)
        results[n]["rows"].append(r)
        print("accuracy [%2d/%d] %-10s %-15s %-42s error %+.3e  step time %7.3f s  (%d steps, %d tets)  %.0f s"
              % (i, len(plan), n, knob, label[:42], r["error"], r["wall"], r["steps"], r["nTets"],
                 time.time() - t0), flush=True)
    for n, res in results.items():
        knobs = {}
        for r in res["rows"]:
            knobs.setdefault(r["knob"], []).append(r)
        res["best"] = {k: bestLevel(rows, PROBLEMS[n][5]) for k, rows in knobs.items()}
        sizes = [r for r in knobs.get("element size", []) if "h" in r]
        if len(sizes) >= 3:
            res["order"] = acclib.fitOrder([r["h"] for r in sizes], [r["error"] for r in sizes])
            res["orderFine"] = acclib.fitOrder([r["h"] for r in sizes[-3:]], [r["error"] for r in sizes[-3:]])
    out = dict(mode="short" if a.short else "full", seconds=time.time() - t0, problems=results)
    path = os.path.join(a.out, "accuracy.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print("accuracy: wrote %s (%.0f s)" % (path, time.time() - t0), flush=True)
    import report
    pngs = report.plots(out, a.out)
    print("accuracy: plots %s" % ", ".join(pngs), flush=True)
    if not a.short and not a.no_doc and not a.only:
        doc = report.writeDoc(out, a.out)
        print("accuracy: wrote %s" % doc, flush=True)


if __name__ == "__main__":
    main()
