"""The time-to-solution benchmark's bookkeeping (scripts/bench/
bench_time_to_solution.py, bench_schema.py, perf_tables.py): a whole run's
wall time is measured or null and projected, never made up; a missing scene
or full run fails `make bench`; the doc's table is printed from the newest
kept JSON."""
import copy
import glob
import json
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))

import bench_schema  # noqa: E402

PY = "/usr/bin/python3.11"
SCENES = [(n, x) for n in ("two_rooks", "king_and_pawns", "forty_front") for x in ("766x", "real_size")]


def _lever(rate):
    keys = ("wall_s_per_simulated_s", "cpu_s_per_simulated_s", "cg_iterations_per_step", "pieces_awake", "load1")
    value = {"cpu_s_per_simulated_s": 1.5 * rate}
    return {"settings": {}, "summary": {k: {"n": 1, "min": value.get(k, rate), "median": value.get(k, rate),
                                            "max": value.get(k, rate)} for k in keys}}


def _log():
    """A small time_to_solution.json as bench_time_to_solution.py writes it."""
    scenes = {}
    for n, x in SCENES:
        scenes["%s_%s" % (n, x)] = {
            "name": n, "scene": n, "scale": 766 if x == "766x" else 1, "pieces": 2, "pieces_awake": 2, "rounds": 3,
            "levers": {"jacobi": _lever(20.0), "cholesky": _lever(10.0)},
            "wall_s_per_simulated_s": {"old": 20.0, "new": 10.0}, "cpu_s_per_simulated_s": {"old": 30.0, "new": 15.0},
            "cg_iterations_per_step": {"old": 20.0, "new": 1.0}, "load1": {"min": 1.0, "median": 2.0},
            "projected_full_run": {"wall_s": 5.0, "simulated_s": 0.5}}
    full = {n: {"wall_s": None, "status": "not run", "projected_wall_s": 3.6e4}
            for n in ("forty_real_size_mu0.1", "forty_real_size_mu0.5")}
    return {"benchmark": "bench_time_to_solution", "date": "2026-11-28T18:00:00Z", "threads": 2, "old": "jacobi",
            "new": "cholesky", "levers": {"jacobi": {}, "cholesky": {}}, "scenes": scenes, "full_runs": full}


def _problems(tmp_path, d):
    (tmp_path / "time_to_solution.json").write_text(json.dumps(d))
    return [p for p in bench_schema.checkOutput(str(tmp_path)) if "time_to_solution.json" in p]


def test_a_forty_line_not_run_is_null_with_its_projection(tmp_path):
    assert _problems(tmp_path, _log()) == []


def test_a_missing_scene_or_full_run_fails_the_check(tmp_path):
    d = _log()
    del d["scenes"]["forty_front_real_size"]
    assert any("lacks scenes.forty_front_real_size.scale" in p for p in _problems(tmp_path, d))
    d = _log()
    del d["full_runs"]["forty_real_size_mu0.5"]
    assert any("lacks full_runs.forty_real_size_mu0.5.wall_s" in p for p in _problems(tmp_path, d))
    d = _log()
    del d["scenes"]["two_rooks_766x"]["wall_s_per_simulated_s"]["old"]
    assert any("wall_s_per_simulated_s.old" in p for p in _problems(tmp_path, d))


def test_a_whole_run_is_measured_or_null_never_made_up(tmp_path):
    d = _log()
    del d["full_runs"]["forty_real_size_mu0.1"]["projected_wall_s"]
    assert any("forty_real_size_mu0.1: wall_s null needs" in p for p in _problems(tmp_path, d))
    d = _log()
    d["full_runs"]["forty_real_size_mu0.1"]["wall_s"] = 3.6e4      # a figure with status "not run"
    assert any("needs status 'measured'" in p for p in _problems(tmp_path, d))
    d = _log()
    d["full_runs"]["forty_real_size_mu0.1"].update(wall_s=3.6e4, status="measured")
    assert _problems(tmp_path, copy.deepcopy(d)) == []


def test_the_table_prints_measured_and_projected_figures(tmp_path):
    p = tmp_path / "tts.json"
    p.write_text(json.dumps(_log()))
    out = subprocess.run([PY, os.path.join(ROOT, "scripts", "bench", "perf_tables.py"), "timeToSolution", str(p)],
                         capture_output=True, text=True, check=True).stdout
    row = [x for x in out.splitlines() if x.startswith("| forty_front | real size")][0]
    assert "20 (30) / 10 (15) | 2.00 |" in row, row
    assert "| forty_real_size_mu0.1 | 10.0 h (CPU —) | not run; projected |" in out, out


def test_the_doc_table_comes_from_the_newest_kept_log():
    """doc/performance.md prints the table from the newest
    bench/logs/time_to_solution_<date>.json, which holds every key."""
    logs = sorted(glob.glob(os.path.join(ROOT, "bench", "logs", "time_to_solution_20??-??-??*.json")))
    assert logs, "no bench/logs/time_to_solution_<date>.json"
    doc = open(os.path.join(ROOT, "doc", "performance.md")).read()
    named = re.findall(r"\{bench-table\} timeToSolution (\S+)", doc)
    assert named == ["bench/logs/" + os.path.basename(logs[-1])], named
    assert bench_schema.checkFile(logs[-1], bench_schema.SCHEMA["time_to_solution.json"],
                                  "time_to_solution.json") == []
