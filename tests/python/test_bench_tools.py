"""The benchmarks' bookkeeping (scripts/bench/benchutil.py, perf_tables.py):
busy runs stay out of the figures, nothing measured is null (never a zero or
a copy), and the doc's tables are printed from the committed JSON."""
import glob
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))

import benchutil  # noqa: E402

PY = "/usr/bin/python3.11"   # the interpreter YADE runs (a child process, not YADE itself)


def test_statistics_of_nothing_is_null_not_zero():
    assert benchutil.stats([]) is None
    assert benchutil.stats([None, None]) is None
    assert benchutil.stats([3.0, 1.0, 2.0]) == {"n": 3, "min": 1.0, "median": 2.0, "max": 3.0}


def test_busy_runs_are_left_out_of_the_clean_figures():
    runs = [{"ms": 1.0, "busy": False}, {"ms": 2.0, "busy": False}, {"ms": 50.0, "busy": True}]
    s = benchutil.summarise(runs, ["ms"])
    assert s["clean"]["ms"] == {"n": 2, "min": 1.0, "median": 1.5, "max": 2.0}
    assert s["all"]["ms"]["max"] == 50.0
    assert benchutil.best(s, "ms") == (1.5, "quiet runs")
    allBusy = benchutil.summarise([dict(r, busy=True) for r in runs], ["ms"])
    assert allBusy["clean"]["ms"] is None
    assert benchutil.best(allBusy, "ms") == (2.0, "all runs (every run busy)")


def test_a_load_probe_sees_another_process_using_cpu():
    """A run during which a child process spins is flagged busy."""
    probe = benchutil.LoadProbe()
    spinner = subprocess.Popen([PY, "-c", "import time\nt=time.time()\nwhile time.time()-t<1.0: pass"])
    spinner.wait()
    rec = probe.finish(1.0)
    assert rec["other_cores"] > 0.5, rec
    assert rec["busy"]


@pytest.mark.parametrize("kind", ["elements", "roofline", "cubes27", "shogi", "effects", "ops"])
def test_doc_tables_print_from_the_committed_json(kind):
    name = {"ops": "kernel_ops"}.get(kind, kind)
    files = sorted(glob.glob(os.path.join(ROOT, "bench", "logs", "%s_20??-??-??.json" % name)))
    assert files, "no bench/logs/%s_<date>.json" % name
    out = subprocess.run([PY, os.path.join(ROOT, "scripts", "bench", "perf_tables.py"), kind, files[-1]],
                         capture_output=True, text=True, check=True).stdout
    assert out.count("\n| ") >= 2, out


def test_every_kept_benchmark_log_holds_the_keys_the_docs_read():
    import bench_schema
    assert bench_schema.checkLogs(os.path.join(ROOT, "bench", "logs")) == []


def test_the_json_check_names_a_missing_file_and_a_missing_key(tmp_path):
    import bench_schema
    problems = bench_schema.checkOutput(str(tmp_path))
    assert any("spheres.json: missing" in p for p in problems)
    (tmp_path / "spheres.json").write_text(json.dumps({"benchmark": "bench_spheres", "near": {}}))
    problems = bench_schema.checkOutput(str(tmp_path))
    assert any("spheres.json: lacks far.coupling_ms_per_step" in p for p in problems)
    assert any("spheres.json: lacks near.coupling_ms_per_step" in p for p in problems)
    # A kept log is recognised by its "benchmark" field.
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "anything.json").write_text(json.dumps({"benchmark": "bench_effects", "date": "x"}))
    assert any("anything.json: lacks threads" in p for p in bench_schema.checkLogs(str(logs)))


def _effectsLog(date, qdemOn=(2.0, 2.2, 4.0), qdemOff=(1.0, 1.1, 2.0)):
    """A small effects.json as bench_effects.py writes it: three rounds."""
    import bench_effects
    runs = {"on": [{"ms_per_step": 3 * q, "qdem_ms_per_step": q, "ms_per_step_on_cpu": q, "busy": True}
                   for q in qdemOn],
            "off": [{"ms_per_step": 3 * q, "qdem_ms_per_step": q, "ms_per_step_on_cpu": q, "busy": True}
                    for q in qdemOff], "zero": []}
    e = bench_effects.summariseEffect(runs, runs["off"])
    return {"benchmark": "bench_effects", "date": date, "tets": 10, "threads": 2, "steps": 5, "rounds": 3,
            "statistic": "paired ratios", "effects": {"viscosity": e}}


def test_effects_table_judges_on_paired_ratios_and_minima(tmp_path):
    """The table's ratios are per-round (on / off of the same round: 2.0,
    2.0, 2.0 here, although the rounds' figures double from the first to the
    last), its ms per step the minima; --doc writes only between the markers."""
    log = tmp_path / "effects.json"
    log.write_text(json.dumps(_effectsLog("2026-11-28T00:00:00Z")))
    script = os.path.join(ROOT, "scripts", "bench", "perf_tables.py")
    out = subprocess.run([PY, script, "effects", str(log)], capture_output=True, text=True, check=True).stdout
    row = [line for line in out.splitlines() if line.startswith("| viscosity")][0].split("|")
    assert row[2].strip() == "2.00 (2.00–2.00)"          # on / off on CPU, paired
    assert row[4].strip() == "2.00 (2.00–2.00)"          # on / off, QDEM's share, paired
    assert row[3].strip() == "—"                         # no zero-valued runs: not measured
    assert row[7].strip() == "2.00 / 1.00 / —"           # QDEM's share, ms per step, minima
    assert row[8].strip() == "6.00 / 3.00 / —"           # the whole step, minima
    doc = tmp_path / "doc.md"
    doc.write_text("# A\n\nbefore\n<!-- perf_tables.py effects: begin -->\nold table\n"
                   "<!-- perf_tables.py effects: end -->\nafter\n")
    subprocess.run([PY, script, "effects", str(log), "--doc", str(doc)], check=True)
    text = doc.read_text()
    assert text.startswith("# A\n\nbefore\n<!-- perf_tables.py effects: begin -->\n")
    assert text.endswith("<!-- perf_tables.py effects: end -->\nafter\n")
    assert "old table" not in text and "| viscosity | 2.00 (2.00–2.00) | — | 2.00 (2.00–2.00) |" in text


def test_an_effects_log_must_hold_qdems_share_from_the_day_it_was_written(tmp_path):
    import bench_schema
    d = _effectsLog("2026-11-28T00:00:00Z")
    del d["effects"]["viscosity"]["qdem"]
    (tmp_path / "new.json").write_text(json.dumps(d))
    old = _effectsLog("2026-11-24T12:00:00Z")
    for k in ("qdem", "paired", "on_cpu"):
        del old["effects"]["viscosity"][k]
    del old["statistic"]
    (tmp_path / "old.json").write_text(json.dumps(old))
    problems = bench_schema.checkLogs(str(tmp_path))
    assert problems == ["%s: lacks effects.[].qdem.all (at [].qdem)" % (tmp_path / "new.json")], problems
