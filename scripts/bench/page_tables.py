"""Tables of doc/parallel.md ("Equal to serial, to rounding") and
doc/shogi.md, printed (Markdown) from the JSON kept in bench/logs/; they
join perf_tables.GENERATORS, so the ``bench-table`` directive prints them:

    /usr/bin/python3.11 scripts/bench/perf_tables.py equalToSerial bench/logs/mpi_equal_to_serial.json \\
        bench/logs/mpi_spheres.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py shogiPieces bench/logs/shogi_pieces.json
    /usr/bin/python3.11 scripts/bench/perf_tables.py shogiScales bench/logs/shogi_scales_2026-11-24.json
    (and shogiScaleCost, shogiFirstHitCost, shogiScaleRuns, shogiCostInRun, shogiSoft, shogiStart)
    /usr/bin/python3.11 scripts/bench/perf_tables.py precond bench/logs/precond_two_rooks_1thread.json \
        bench/logs/precond_two_rooks_2threads.json            (doc/performance.md)

A figure printed here is never typed: scene descriptions are words, and
every number in a row comes from the JSON."""
import json

from doc_figures import sig


def _e(x):
    """A relative difference: one significant digit and its exponent (0 when exact)."""
    return "0" if x == 0 else "%.1e" % x


def _range(xs):
    """'a to b' of relative differences (one figure when they print alike)."""
    lo, hi = _e(min(xs)), _e(max(xs))
    return lo if lo == hi else "%s to %s" % (lo, hi)


def _ranks(part):
    """The P of a part ('P2', 'P3', ...) and their rows."""
    ps = sorted((k for k in part if k.startswith("P") and k[1:].isdigit()), key=lambda k: int(k[1:]))
    return ", ".join(p[1:] for p in ps), [part[p] for p in ps]


def _its(s):
    """'3 CG iterations', '1 CG iteration', '0-1 CG iterations' (min-max over the steps)."""
    n = "%d" % s["min"] if s["min"] == s["max"] else "%d-%d" % (s["min"], s["max"])
    return "%s CG iteration%s" % (n, "" if n == "1" else "s")


def equalToSerial(d, spheresJson):
    """max |dx| over the largest displacement, P ranks against one process,
    for QDEM's scenes (mpi_equal_to_serial.json, scripts/mpi/equal_to_serial.py)
    and the YADE spheres and the seed's broad phases (mpi_spheres.json,
    scripts/mpi/spheres_vs_serial.py)."""
    sp = json.load(open(spheresJson))
    print("| scene (check) | P | max \\|Δx\\| / largest displacement |")
    print("|---|---|---|")

    def row(scene, part, text):
        ps, rows = _ranks(part)
        print("| %s | %s | %s |" % (scene, ps, text(rows)))

    cf, ct = d["contactFree"], d["contacts"]
    row("pieces falling on a floor, no piece contacts, {:,} steps (`check_contact_free.py`)".format(cf["steps"]),
        cf, lambda r: _range([x["dxOverDisp"] for x in r]))
    row("slab, sliding and resting cubes, crossed edges, %d steps (`check_contacts.py`)" % ct["steps"], ct,
        lambda r: "%s (serial 1 vs 2 threads: %s)" % (_range([x["dxOverDisp"] for x in r]),
                                                      _range([x["threads2"] for x in r])))
    rb = d["rebalance"]
    _, rbRows = _ranks(rb)
    row("the same, rebalanced mid-run (%s nodes move on %s ranks, contacts open)" % (
        " and ".join(str(x["movedNodes"]) for x in rbRows), _ranks(rb)[0].replace(", ", " and ")), rb,
        lambda r: _range([x["dxOverDisp"] for x in r]))
    row("the same, saved on 3 ranks, loaded on 3, continued (`check_restart.py`)", d["restart"],
        lambda r: "%s against the uninterrupted run" % _e(r[0]["restartVsContOverDisp"]))
    sl = d["sleep"]
    _, slRows = _ranks(sl)
    rest = "all %d come to rest" % sl["threads2"]["pieces"] if all(
        x["asleepAtEnd"] == x["pieces"] for x in slRows) else "not all come to rest"
    row("the same with sleeping pieces (%s, the same asleep at every check), {:,} steps (`check_sleep.py`)".format(
        sl["threads2"]["steps"]) % rest, sl,
        lambda r: "%s, as 1 vs 2 threads serially (%s)" % (_range([x["dxOverDisp"] for x in r]),
                                                            _e(sl["threads2"]["dxOverDisp"])))
    for bp in ("A", "B", "C"):
        row("the contact scene with the seed's broad phase %s, %d steps (`check_contacts.py`)" % (bp, ct["steps"]),
            sp["broadPhases"][bp], lambda r: "%s (serial 1 vs 2 threads: %s)" % (
                _range([x["dxOverDisp"] for x in r]), _range([x["threads2"] for x in r])))
    im, iw = d["implicit"], d["implicitWarm"]
    _, imRows = _ranks(im)
    _, iwRows = _ranks(iw)
    same = lambda rows, serial=True: (  # noqa: E731
        "; the same iteration count on every rank at every step" + (", and as serially" if serial else "")
        if all(x["sameIterationsEveryRank"] and (x["sameIterationsAsSerial"] or not serial) for x in rows)
        else "; iteration counts differ between ranks")
    row("implicit viscosity (%s preconditioner): the falling pieces, %d steps at 0.5 of the elastic limit (%.0f "
        "times the explicit viscous one), every solve from zero (`viscousWarmStart=False`), %s per step "
        "(`check_implicit_viscosity.py`)" % (imRows[0]["preconditioner"], im["steps"],
                                                 imRows[0]["dtOverExplicitLimit"],
                                                 _its(imRows[0]["iterations"])), im,
        lambda r: "%s (serial 1 vs 2 threads: %s)%s" % (_range([x["dxOverDisp"] for x in r]),
                                                         _range([x["threads2"] for x in r]), same(r)))
    iwRanks, _ = _ranks(iw)
    row("the same warm-started (the default: each solve from the last step's change), %s per step (median %g), "
        "with a rebalance forced half-way (every piece split along the curve then: %s nodes move on %s ranks; "
        "their last changes move with them, and the next solve takes %s iterations) (`... warm`)" % (
            _its(iwRows[-1]["iterations"]), iwRows[-1]["iterations"]["median"],
            " and ".join(str(x["movedNodes"]) for x in iwRows), iwRanks.replace(", ", " and "),
            " and ".join(str(x["iterations"]["afterRebalance"]) for x in iwRows)), iw,
        lambda r: "%s (serial 1 vs 2 threads: %s: the warm start carries each step's solve error into the next, so "
                  "rounding differences grow within the tolerance, doc/formulation.md 2.1)%s" % (
                      ", ".join(_e(x["dxOverDisp"]) for x in r), _range([x["threads2"] for x in r]),
                      same(r, serial=False)))
    for scene, text in (("drop", "YADE spheres dropped on a block (`yade_spheres.py drop`)"),
                        ("clump", "a 3-sphere clump rolling and hopping across a cut of a slab (`... clump`)")):
        s = sp["spheres"][scene]
        row(text, s, lambda r: "%s; sphere states %s of their largest value (serial 1 vs 2 threads: %s; %s)" % (
            _range([x["dxOverDisp"] for x in r]), _range([x["dSphereOverMax"] for x in r]),
            _e(s["threads2"]["dxOverDisp"]), _e(s["threads2"]["dSphereOverMax"])))
    rs = sp["restart"]
    row("the spheres, a rebalance forced (spheres resting on the block, %d nodes move) and O.save there; O.load and "
        "the last steps again" % rs["movedNodes"], {"P3": rs},
        lambda r: "as above; the reloaded end against the continued one: %s, sphere states %s" % (
            _e(r[0]["reloadedDxOverDisp"]), _e(r[0]["reloadedDSphereOverMax"])))


# -- doc/shogi.md -----------------------------------------------------------------

ORDER = ("king", "rook", "bishop", "gold", "silver", "knight", "lance", "pawn")


def shogiPieces(d):
    """The eight kinds' sizes and mesh counts (scripts/shogi/pieces.py)."""
    print("| kind | size [mm] | nodes | surface nodes | tets |")
    print("| --- | --- | --- | --- | --- |")
    for k in ORDER:
        r = d[k]
        print("| %s | %.2f × %.2f × %.2f | {:,} | {:,} | {:,} |".format(r["nodes"], r["surface_nodes"], r["tets"])
              % (k, r["height_mm"], r["width_mm"], r["thickness_mm"]))


def _scales(d):
    return sorted(d["scales"].items(), key=lambda kv: -float(kv[0]))


def _length(m):
    return "%s mm" % sig(1000 * m, 3) if m < 0.1 else "%s m" % sig(m, 3)


def shogiScales(d):
    """How the steps and the damping scale with the size (scripts/shogi/scales.py)."""
    print("| scale | rook height | sqrt(H/g) | w_1 [rad/s] | xi_1 | elastic limit | explicit viscous limit | "
          "xi_max = ratio / 2 | contact limit |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for s, r in _scales(d):
        print("| %s | %s | %s s | %s | %s | %.1e s | %.2e s | %s | %.1e s |" % (
            s, _length(r["height_m"]), sig(r["froude_time_unit_s"], 4), sig(r["first_mode_rad_per_s"], 3),
            sig(r["first_mode_damping_ratio"], 2), r["elastic_dt"], r["viscous_dt"],
            sig(r["elastic_dt"] / r["viscous_dt"] / 2, 2), r["contact_dt"]))


def shogiScaleCost(d):
    """Explicit against implicit per step and per simulated second (scales.py's short runs)."""
    print("| scale | explicit dt | ms per step | CPU s per simulated s | implicit dt | CG iterations (from 0) | "
          "ms per step (from 0) | CPU s per simulated s | explicit / implicit |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for s, r in _scales(d):
        ex, im, cold = r["explicit"], r["implicit"], r["implicit_cold"]
        print("| %s | %.2e s | %s | %s | %.2e s | %.0f (%.0f) | %s (%s) | %s | %s |" % (
            s, ex["dt"], sig(ex["cpu_ms_per_step"], 2), sig(ex["cpu_s_per_simulated_s"], 2), im["dt"],
            im["cg_iterations_per_step"], cold["cg_iterations_per_step"], sig(im["cpu_ms_per_step"], 2),
            sig(cold["cpu_ms_per_step"], 2), sig(im["cpu_s_per_simulated_s"], 2), sig(r["explicit_over_implicit"], 2)))


def duration(seconds):
    """s, min, h or days, two significant digits."""
    for unit, size in (("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= 2 * size:
            return "%s %s" % (sig(seconds / size, 2), unit)
    return "%s s" % sig(seconds, 2)


def shogiFirstHitCost(d):
    """CPU time to the second rook's hit, by Froude scaling of the 766x hit time."""
    print("| scale | second rook hit at | explicit: CPU to the hit | implicit: CPU to the hit |")
    print("| --- | --- | --- | --- |")
    for s, r in _scales(d):
        print("| %s | %s s | %s | %s |" % (s, sig(r["first_hit_s"], 4), duration(r["explicit"]["cpu_s_to_first_hit"]),
                                          duration(r["implicit"]["cpu_s_to_first_hit"])))


def shogiScaleRuns(d):
    """The runs of scripts/shogi/scales.table, times after the push (in brackets at 766x)."""
    print("| scale | viscosity | friction | dt | simulated (at 766x) | second rook hit (at 766x) | first rook fallen "
          "(at 766x) | second rook fallen (at 766x) | CG iterations per step | wall s per simulated s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def t(r, key, i=None):
        v, w = (r[key], r[key + "_at_766x"]) if i is None else (r[key][i], r[key + "_at_766x"][i])
        if v is None:
            return "—"
        return "%s s" % sig(v, 4) if r["scale"] == d["table1_scale"] else "%s s (%s s)" % (sig(v, 4), sig(w, 4))

    for r in sorted(d["runs"], key=lambda r: (-r["scale"], r["viscous"], r["frictionPiece"])):
        print("| %s | %s | %s | %.3g s | %s | %s | %s | %s | %s | %s |" % (
            r["scale"], r["viscous"], r["frictionPiece"], r["dt"], t(r, "simulated_s"), t(r, "firstHit_s", 1),
            t(r, "fallen_s", 0), t(r, "fallen_s", 1),
            "%.0f" % r["cg_iterations_per_step"] if r["viscous"] == "implicit" else "-",
            sig(r["wall_s_per_simulated_s"], 3)))


def shogiCostInRun(d, scalesJson):
    """Warm against from-zero solves from the real-size runs' checkpoints
    (cost_in_run.py), against the explicit cost at the same scale (scales.py)."""
    scales = json.load(open(scalesJson))["scales"]
    print("| run, from | CG iterations warm (from 0) | ms per step warm (from 0) | CPU s per simulated s warm | "
          "explicit / implicit warm |")
    print("| --- | --- | --- | --- | --- |")
    for name, r in sorted(d["runs"].items()):
        w, z = r["warm"], r["from_zero"]
        perSimulated = 1e-3 * w["cpu_ms_per_step"] / r["dt"]
        print("| %s, friction %s, t = %.3f s | %.0f (%.0f) | %s (%s) | %s | %s |" % (
            "real size" if r["scale"] == 1 else "%s×" % r["scale"], r["frictionPiece"], r["from_s"],
            w["cg_iterations_per_step"], z["cg_iterations_per_step"], sig(w["cpu_ms_per_step"], 2),
            sig(z["cpu_ms_per_step"], 3), sig(perSimulated, 2),
            sig(scales[str(r["scale"])]["explicit"]["cpu_s_per_simulated_s"] / perSimulated, 2)))


def shogiSoft(d, *more):
    """The soft material's short scenes (domino.py's hits.json of each run,
    gathered in shogi_soft.json): first hits and falls per piece."""
    print("| scene | piece friction | simulated | pieces hit | first hits [s] | fallen (70 % height) [s] | "
          "wall s per simulated s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, r in d["runs"].items():
        hit = [t for t in r["firstHit_s"] if t is not None]
        print("| %s | %s | %s s | %d of %d | %s | %s | %s |" % (
            r["scene"], r["frictionPiece"], sig(r["simulated_s"], 3), len(hit), r["pieces"],
            " / ".join("—" if t is None else sig(t, 3) for t in r["firstHit_s"][1:]),
            " / ".join("—" if t is None else sig(t, 3) for t in r["fallen_s"]), sig(r["wall_s_per_simulated_s"], 2)))


def precond(d, *more):
    """The implicit viscous solve's preconditioners on the two rooks
    (scripts/shogi/precond_bench.py: one JSON per thread count): CG
    iterations and CPU and wall ms per step, min / median over the rounds."""
    print("| preconditioner | threads | CG iterations per step | CPU ms per step, min / median | "
          "wall ms per step, min / median |")
    print("| --- | --- | --- | --- | --- |")
    for run in [d] + [json.load(open(p)) for p in more]:
        for name, s in run["summary"].items():
            print("| %s | %d | %s | %s / %s | %s / %s |" % (
                name, run["threads"], sig(s["cg_iterations_per_step"]["median"], 4),
                sig(s["cpu_ms_per_step"]["min"], 3), sig(s["cpu_ms_per_step"]["median"], 3),
                sig(s["ms_per_step"]["min"], 3), sig(s["ms_per_step"]["median"], 3)))


ARCH_SCENES = ("cubes27", "shogi", "spheres", "restart")


def archCompare(index):
    """Old build against new of each step of the restructuring
    (doc/architecture.md; arch_compare_index.json names each change's
    compare_builds.py JSON): max |dx| over the largest displacement D per
    scene and thread count, the restart with the old build's state file
    resumed by the new build, and the licence (one build at 1 against 2
    threads, over D) of each scene."""
    import os
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
    print("| change | threads | %s | old state resumed by new | 1 vs 2 threads (licence: %s) | JSON |"
          % (" | ".join(ARCH_SCENES), " / ".join(ARCH_SCENES)))
    print("|%s" % ("---|" * (len(ARCH_SCENES) + 5)))
    for row in index["rows"]:
        d = json.load(open(os.path.join(root, row["json"])))
        sc = d["scenes"]
        for i, t in enumerate(d["threads"]):
            cells = []
            for name in ARCH_SCENES:
                r = sc.get(name, {}).get("old_vs_new", {}).get(str(t))
                cells.append("" if r is None else _e(r["ratio"]))
            across = sc.get("restart", {}).get("restart_across_builds", {}).get(str(t))
            resumed = "" if across is None else _e(across["max_dx_old_state_resumed_by_new_vs_by_old"] /
                                                     sc["restart"]["largest_displacement"])
            licence = " / ".join("" if name not in sc else _e(sc[name]["licence_ratio"]) for name in ARCH_SCENES) \
                if t > 1 else ""
            print("| %s | %d | %s | %s | %s | %s |" % (row["change"] if i == 0 else "", t, " | ".join(cells),
                                                       resumed, licence, "`%s`" % row["json"] if i == 0 else ""))


PAGE_GENERATORS = {f.__name__: f for f in (
    equalToSerial, shogiPieces, shogiScales, shogiScaleCost, shogiFirstHitCost, shogiScaleRuns, shogiCostInRun,
    shogiSoft, precond, archCompare)}
