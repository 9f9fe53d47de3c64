"""Old build against new build, interleaved in one sitting (issue 13 item 7):
every round runs each benchmark once with each build, the order old/new
alternating from round to round and from benchmark to benchmark, the load
average read before and after every run.  Raw figures go to the JSON file
(rewritten after every run, so an interrupted sitting keeps what it measured).

    /usr/bin/python3.11 scripts/bench/arch/arch_old_vs_new_run.py OLD_BUILD NEW_BUILD ROUNDS OUT.json SHOGI_CACHE.npz
"""
import json
import os
import resource
import subprocess
import sys
import time

old, new, rounds, outPath, shogiCache = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
tmp = "/tmp/archbench/runs"
os.makedirs(tmp, exist_ok=True)

ELEMENT_ARGS = ["50", "3", "1"]            # steps, cubes per axis (default size), repeats per process
CUBES_STEPS = "600"                        # run_all.sh's default (one round per process: see below)
SHOGI_STEPS = "200"                        # run_all.sh's default
SPHERE_ARGS = ["--spheres", "5000", "--warm", "1000", "--steps", "200"]


def commands(build, tag, r):
    out = os.path.join(tmp, "%s_r%d" % (tag, r))
    return {
        "elements": ([os.path.join(build, "bench_elements")] + ELEMENT_ARGS, None),
        "cubes27": (["/usr/bin/python3.11", "scripts/bench/bench_cubes27.py", "--steps", CUBES_STEPS, "--rounds", "1",
                     "--out", out + "_cubes"], os.path.join(out + "_cubes", "cubes27.json")),
        "shogi": (["/usr/bin/python3.11", "scripts/bench/arch/arch_shogi_cached.py", shogiCache, SHOGI_STEPS], None),
        "spheres": (["yade", "-j", "2", "-n", "-x", "scripts/bench/bench_spheres.py"] + SPHERE_ARGS
                    + ["--out", out + "_spheres"], os.path.join(out + "_spheres", "spheres.json")),
    }


def cpuBusy():
    """Seconds of CPU time the whole machine has spent busy (all cores)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:9]]
    return (sum(v) - v[3] - v[4]) / os.sysconf("SC_CLK_TCK")


def childCpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def loadavg():
    with open("/proc/loadavg") as f:
        return f.read().split()[:4]


def runOne(build, tag, r, name):
    cmd, jsonFile = commands(build, tag, r)[name]
    env = dict(os.environ, OMP_WAIT_POLICY="passive", PYTHONPATH=os.path.join(build, "python"))
    before = loadavg()
    busy0, own0 = cpuBusy(), childCpu()
    t0 = time.time()
    p = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True)
    wall = time.time() - t0
    busy1, own1 = cpuBusy(), childCpu()
    after = loadavg()
    # what other processes kept busy during the run, in cores (machine busy
    # time minus the benchmark's own CPU time, over the wall time)
    others = max(0.0, (busy1 - busy0) - (own1 - own0)) / wall
    rec = {"bench": name, "build": tag, "build_path": build, "round": r, "cmd": cmd,
           "env": {"OMP_WAIT_POLICY": "passive", "PYTHONPATH": env["PYTHONPATH"]}, "cwd": root,
           "loadavg_before": before, "loadavg_after": after, "process_wall_s": wall,
           "process_cpu_s": own1 - own0, "others_cores_during_run": others, "exit": p.returncode,
           "utc_start": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t0))}
    try:
        if jsonFile:
            with open(jsonFile) as f:
                rec["result"] = json.load(f)
        else:
            rec["result"] = json.loads(p.stdout.strip().splitlines()[-1])
    except Exception as e:  # keep the failure visible in the raw file
        rec["error"] = "%s; stderr tail: %s" % (e, p.stderr[-2000:])
    return rec


def waitQuiet():
    """With ARCH_GATE=1: before each pair, wait (up to 60 s) for a 2-second
    window in which other processes use under 0.3 core, so that more pairs
    land in quiet stretches of the shared machine; returns the seconds waited."""
    if os.environ.get("ARCH_GATE") != "1":
        return 0.0
    t0 = time.time()
    while time.time() - t0 < 60:
        b0 = cpuBusy()
        time.sleep(2)
        if (cpuBusy() - b0) / 2 < 0.3:
            break
    return time.time() - t0


stopAt = time.time() + float(os.environ.get("ARCH_TIME_LIMIT", "1e9"))
res = {"old_build": old, "new_build": new, "rounds": rounds, "runs": []}
# ARCH_BENCHES=cubes27,elements: only those (default: all four)
benches = os.environ.get("ARCH_BENCHES", "elements,cubes27,shogi,spheres").split(",")
for r in range(rounds):
    if time.time() > stopAt:
        break
    for b, name in enumerate(benches):
        waited = waitQuiet()
        order = [(old, "old"), (new, "new")] if (r + b) % 2 == 0 else [(new, "new"), (old, "old")]
        for build, tag in order:
            rec = runOne(build, tag, r, name)
            rec["waited_for_quiet_s"] = waited
            res["runs"].append(rec)
            print("round %d %-8s %s: %.1f s, others %.2f cores, load %s -> %s%s" % (r, name, tag, rec["process_wall_s"], rec["others_cores_during_run"],
                  rec["loadavg_before"][0], rec["loadavg_after"][0], "  ERROR " + rec["error"] if "error" in rec else ""),
                  flush=True)
            with open(outPath, "w") as f:
                json.dump(res, f, indent=1)
