"""doc/accuracy.md is generated, never typed: its text is what
scripts/accuracy/report.py writes from the kept JSON of the run it shows
(bench/logs/accuracy.json, with the implicit-viscosity and mass-scaling
studies' bench/logs/implicit_viscosity.json and mass_scaling.json).  A
figure edited by hand, or a study re-run without regenerating the page,
fails here; `make accuracy` regenerates both."""
import json
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "accuracy"))


def test_accuracy_page_is_what_the_kept_json_generates(tmp_path):
    import report
    with open(os.path.join(ROOT, "bench", "logs", "accuracy.json")) as f:
        kept = json.load(f)
    assert kept["mode"] == "full"
    # tmp_path holds no study JSON: the kept ones in bench/logs are used.
    text = report.docText(kept, str(tmp_path))
    with open(os.path.join(ROOT, "doc", "accuracy.md")) as f:
        page = f.read()
    if text != page:
        a, b = text.splitlines(), page.splitlines()
        i = next((k for k in range(min(len(a), len(b))) if a[k] != b[k]), min(len(a), len(b)))
        raise AssertionError("doc/accuracy.md differs from what bench/logs/accuracy.json generates, first at line "
                             "%d:\n  generated: %s\n  page:      %s\nRun make accuracy (or edit report.py, not "
                             "the page)." % (i + 1, a[i] if i < len(a) else "<end>", b[i] if i < len(b) else "<end>"))
