"""Histogram of the stable step the engine accepts over the exact one, per
family of sampled states (doc/formulation.md, "How far below the exact step").

The ratios come from the property test: build, then
    QDEM_STABLE_STEP_JSON=bench/logs/stable_step_ratios.json \\
        build/qdem_tests --gtest_filter='StableStepProperty*'
    /usr/bin/python3.11 scripts/doc/stable_step_histogram.py
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default="bench/logs/stable_step_ratios.json")
    ap.add_argument("--out", default="doc/img/stable_step_ratios.png")
    a = ap.parse_args()
    with open(a.data) as f:
        ratios = json.load(f)
    fig, ax = plt.subplots(figsize=(7, 3.8))
    bins = np.linspace(0.4, 1.0, 49)  # (values within the test's 1e-6 of 1 in the last bin)
    for family, r in sorted(ratios.items()):
        r = np.asarray(r)
        ax.hist(np.clip(r, bins[0], bins[-1] - 1e-9), bins=bins, histtype="step", linewidth=1.5,
                label="%s (%d; min %.2f, median %.2f, max %.4f)" % (family, len(r), r.min(), np.median(r), r.max()))
    ax.axvline(1.0, color="k", linestyle="--", linewidth=1)
    ax.set_xlabel("accepted step / exact stable step of the linearised update")
    ax.set_ylabel("sampled states")
    ax.set_yscale("log")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("The stable step is never optimistic (1 = exact)", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
