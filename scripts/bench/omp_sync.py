"""The price of one OpenMP synchronisation (fork, barrier, join; 2 threads)
under each wait policy, interleaved: build/omp_sync run `--rounds` times per
policy, alternating, each run in a fresh process (libgomp reads the policy
once, at start).  Policies: 'passive' (a waiting thread sleeps at once: what
every benchmark here uses, so that spinning threads do not steal a shared
machine's cores) and 'default' (no OMP_WAIT_POLICY: libgomp spins a while,
then sleeps; what a YADE user gets).

    /usr/bin/python3.11 scripts/bench/omp_sync.py [--build build] [--rounds 5] [--out out/bench/omp_sync.json]
                                                  [--halt-poll-ns NS]

--halt-poll-ns (root, KVM guests with the haltpoll idle driver): run with
the guest's idle-poll window set to NS nanoseconds, restored afterwards
(this machine has 0: an idle vCPU halts at once, and a sleeping thread
waits for the hypervisor to wake it).

Prints a table of the medians over the rounds (each round's figure is the
median over its iterations) and writes every run's JSON."""
import argparse
import json
import os
import statistics
import subprocess
import sys

POLICIES = {"passive": {"OMP_WAIT_POLICY": "passive"}, "default": {}}
HALT_POLL = "/sys/module/haltpoll/parameters/guest_halt_poll_ns"


def run(binary, policy, iterations):
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    env.update(POLICIES[policy])
    out = subprocess.run([binary, "--iterations", str(iterations)], env=env, capture_output=True, text=True,
                         timeout=600, check=True).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--iterations", type=int, default=200)
    ap.add_argument("--out", default="out/bench/omp_sync.json")
    ap.add_argument("--halt-poll-ns", type=int, default=None)
    a = ap.parse_args()
    if a.halt_poll_ns is None:
        measure(a)
        return
    if a.halt_poll_ns < 0:
        ap.error("--halt-poll-ns must be at least 0")
    try:
        with open(HALT_POLL) as f:
            before = f.read().strip()
        with open(HALT_POLL, "w") as f:
            f.write(str(a.halt_poll_ns))
    except OSError as e:
        sys.exit("omp_sync.py: cannot set %s (%s): needs root on a KVM guest with the haltpoll driver" % (HALT_POLL, e))
    try:
        measure(a)
    finally:
        with open(HALT_POLL, "w") as f:
            f.write(before)


def measure(a):
    binary = os.path.join(a.build, "omp_sync")
    if not os.access(binary, os.X_OK):
        sys.exit("omp_sync.py: %s not found: build it first (make build)" % binary)
    runs = {p: [] for p in POLICIES}
    for r in range(a.rounds):
        for p in (POLICIES if r % 2 == 0 else reversed(list(POLICIES))):
            d = run(binary, p, a.iterations)
            runs[p].append(d)
            print("round %d %-8s load %.2f others %.2f: " % (r, p, d["load1"], d["other_cores"]) +
                  "  ".join("serial %g us: fork %.1f barrier %.1f join %.1f" %
                            (q["serial_us"], q["fork"]["median"], q["barrier"]["median"], q["join"]["median"])
                            for q in d["points"]), file=sys.stderr)
    summary = {}
    print("| policy | serial work before | fork, us | barrier, us | join, us |")
    print("| --- | --- | --- | --- | --- |")
    for p, ds in runs.items():
        summary[p] = []
        for i, q in enumerate(ds[0]["points"]):
            row = {"serial_us": q["serial_us"]}
            for kind in ("fork", "barrier", "join"):
                med = [d["points"][i][kind]["median"] for d in ds]
                row[kind] = {"median_of_rounds": statistics.median(med), "min": min(med), "max": max(med)}
            summary[p].append(row)
            print("| %s | %g us | %s |" % (p, q["serial_us"], " | ".join(
                "%.1f (%.1f–%.1f)" % (row[k]["median_of_rounds"], row[k]["min"], row[k]["max"])
                for k in ("fork", "barrier", "join"))))
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w") as f:
        json.dump({"benchmark": "omp_sync", "rounds": a.rounds, "summary": summary, "runs": runs}, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
