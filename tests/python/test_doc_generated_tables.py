"""The tables of measured figures on the user pages are printed from the
benchmark JSON kept in bench/logs/ (the ``bench-table`` directive of
doc/_ext/qdemdoc.py, generators in scripts/bench/perf_tables.py), never
typed by hand: every directive's generator runs on its kept JSON, and the
pages of MPI (at scale and the user guide), of the shogi scenes and of
performance hold no Markdown table row with a figure outside one (tables of
pictures aside).

Runs in a second: no Sphinx build (test_doc_site.py builds the site)."""
import contextlib
import glob
import io
import json
import os
import re
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))

import perf_tables  # noqa: E402

# ```{bench-table} kind path [path ...]
DIRECTIVE = re.compile(r"^\s*```\{bench-table\}\s+(\S+)\s+(.+?)\s*$")
# Pages where no table row may carry a figure unless a generator prints it.
GENERATED_ONLY = ["doc/parallel_scaling.md"]
# ... and pages whose tables are all printed, beside committed pictures.
TABLES_GENERATED = GENERATED_ONLY + ["doc/parallel.md", "doc/shogi.md", "doc/performance.md"]


def benchTables():
    """(page, line, kind, paths) of every bench-table directive of the site."""
    out = []
    for page in sorted(glob.glob(os.path.join(ROOT, "doc", "**", "*.md"), recursive=True)):
        for i, line in enumerate(open(page, encoding="utf-8"), 1):
            m = DIRECTIVE.match(line)
            if m:
                out.append((os.path.relpath(page, ROOT), i, m.group(1), m.group(2).split()))
    return out


def run(kind, paths):
    """What the directive prints: the generator on the first JSON, the others as paths."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        perf_tables.GENERATORS[kind](json.load(open(os.path.join(ROOT, paths[0]))),
                                     *[os.path.join(ROOT, p) for p in paths[1:]])
    return buf.getvalue()


def pictureRow(row):
    """Every cell of a table row that holds a digit holds an image (whose path may hold digits)."""
    return all("![" in c for c in row.strip().strip("|").split("|") if re.search(r"\d", c))


def handTypedRows(text):
    """Markdown table rows holding a digit outside a bench-table directive
    (whose content is printed, not typed): (line number, line).  A table of
    pictures (below its rule, every cell with a digit holds an image) is no
    table of figures: its header labels the pictures (friction 0.1, 0.6 s)."""
    lines = text.splitlines()
    rows, i = [], 0
    while i < len(lines):
        if not lines[i].lstrip().startswith("|"):
            i += 1
            continue
        j = i
        while j < len(lines) and lines[j].lstrip().startswith("|"):
            j += 1
        table = list(enumerate(lines[i:j], i + 1))
        body = [x for _, x in table[2:]]
        if not (body and all(pictureRow(x) for x in body)):
            rows += [(k, x.rstrip()) for k, x in table if re.search(r"\d", x)]
        i = j
    return rows


def test_the_mpi_pages_print_their_tables():
    """The moved MPI tables and the mpy table are generated (a lost
    directive would leave a page without its figures)."""
    kinds = {(page, kind) for page, _, kind, _ in benchTables()}
    for kind in ("zoltan", "zoltanByP", "zoltanSlowNetwork", "mpiPingpong", "mpiRanks", "mpiInputs",
                 "mpiEfficiency", "mpiProjection", "mpiPingpongCurve", "mpiRerun", "mpiExtrapolation",
                 "mpiValidation", "mpiMemory"):
        assert ("doc/parallel_scaling.md", kind) in kinds, kind
    assert ("doc/parallel.md", "mpiMpy") in kinds


@pytest.mark.parametrize("page,line,kind,paths", benchTables(),
                         ids=lambda x: x if isinstance(x, str) and not x.startswith("doc") else None)
def test_every_bench_table_prints_from_its_kept_json(page, line, kind, paths):
    """The generator exists, its JSON is kept, and it prints a Markdown
    table (a header, a rule and at least one row)."""
    assert kind in perf_tables.GENERATORS, "%s:%d: no generator %r in perf_tables.py" % (page, line, kind)
    for p in paths:
        assert os.path.isfile(os.path.join(ROOT, p)), "%s:%d: %s is not kept" % (page, line, p)
    rows = [x for x in run(kind, paths).splitlines() if x.startswith("|")]
    assert len(rows) >= 3, "%s:%d: %s printed no table" % (page, line, kind)
    assert not any("nan" in r.lower().split("|") for r in rows)


@pytest.mark.parametrize("page", TABLES_GENERATED)
def test_no_hand_typed_table_of_figures(page):
    """A table of figures on these pages comes from a generator: a
    hand-typed row (a line starting with '|' with a digit) is refused."""
    rows = handTypedRows(open(os.path.join(ROOT, page), encoding="utf-8").read())
    assert rows == [], "%s: table rows typed by hand (print them with a bench-table generator, " \
                       "scripts/bench/perf_tables.py): %s" % (page, rows[:3])


@pytest.mark.parametrize("page", GENERATED_ONLY)
def test_the_plots_are_drawn_from_the_kept_json(page, tmp_path):
    """The page's plots are bench-figure directives drawn by
    scripts/bench/perf_plots.py from kept JSON, not committed images."""
    import perf_plots
    text = open(os.path.join(ROOT, page), encoding="utf-8").read()
    assert not re.search(r"!\[[^]]*\]\(img/", text), "%s: a committed image; draw it with bench-figure" % page
    figures = re.findall(r"^```\{bench-figure\}\s+(\S+)\s+(.+?)\s*$", text, re.M)
    assert figures
    for kind, paths in figures:
        png = tmp_path / ("%s.png" % kind)
        getattr(perf_plots, kind)(str(png), *[os.path.join(ROOT, p) for p in paths.split()])
        assert png.stat().st_size > 10000, kind


def test_hand_typed_check_catches_a_table():
    """The check itself: a typed row with figures is caught, a directive and
    prose with figures are not, nor the labels of a table of pictures."""
    text = ("Text with 1.46 µs.\n\n| P | step |\n|---|---|\n| 2 | 0.79 |\n\n"
            "```{bench-table} mpiValidation x.json\n```\n\n"
            "| friction 0.1 | friction 0.5 |\n| --- | --- |\n| ![](a.png) | ![](b.png) |\n\n"
            "| friction 0.1 | 14 hit |\n| --- | --- |\n| ![](a.png) | 0.54 m/s |\n")
    assert [i for i, _ in handTypedRows(text)] == [5, 14, 16]


def test_the_parallel_and_shogi_pages_print_their_tables():
    """parallel.md's equal-to-serial table and shogi.md's tables are
    generated (a lost directive would leave a page without its figures)."""
    kinds = {(page, kind) for page, _, kind, _ in benchTables()}
    assert ("doc/parallel.md", "equalToSerial") in kinds
    for kind in ("shogiPieces", "shogiSoft", "shogi", "shogiScales", "shogiScaleCost", "shogiCostInRun",
                 "shogiFirstHitCost", "shogiScaleRuns"):
        assert ("doc/shogi.md", kind) in kinds, kind


def test_step_over_work_is_the_stated_formula():
    """(w imbalance tets/P + alpha 2 neighbours_max + beta bytes_max) / (w tets/P),
    with bytes_max the larger of sent and received: no messages leaves the
    imbalance; each term adds its own share."""
    row = {"tets": 6400, "ranks": 64, "imbalance": 1.05, "neighbours_max": 0,
           "bytes_sent_per_step_max": 0, "bytes_received_per_step_max": 0}
    w, alpha, beta = 40e-9, 2e-6, 3e-10
    assert perf_tables.stepOverWork(row, alpha, beta, w) == pytest.approx(1.05, rel=1e-12)
    row.update(neighbours_max=10, bytes_sent_per_step_max=1000, bytes_received_per_step_max=4000)
    share = w * 6400 / 64  # 4 µs
    expect = 1.05 + (alpha * 2 * 10 + beta * 4000) / share
    assert perf_tables.stepOverWork(row, alpha, beta, w) == pytest.approx(expect, rel=1e-12)


def test_the_zoltan_table_matches_the_figures_the_text_quotes():
    """Spot figures the page's prose cites from the generated table
    (P = 64: ours 1.041 of the work on the heap, 1.40 on the slow network;
    Zoltan HSFC's 1.29 against hilbert-split's 1.30 on the mixed scene)."""
    out = run("zoltan", ["bench/logs/mpi_zoltan.json", "bench/logs/mpi.json"])
    top = out.split("P = 16:")[0]
    row = [r for r in top.splitlines() if r.startswith("| pieces | hilbert |")][0].split("|")
    assert (row[9].strip(), row[10].strip()) == ("1.041", "1.404")
    slow = run("zoltanSlowNetwork", ["bench/logs/mpi_zoltan.json", "bench/logs/mpi.json"])
    mixed = [r for r in slow.splitlines() if r.startswith("| mixed |")][0].split("|")
    assert [c.strip() for c in mixed[2:6]] == ["1.35", "1.30", "1.18", "1.29"]


def test_the_performance_and_architecture_pages_print_their_tables():
    """performance.md's tables of measured figures and architecture.md's
    old-against-new table are generated (a lost directive would leave a page
    without its figures, or a typed copy in its place)."""
    kinds = {(page, kind) for page, _, kind, _ in benchTables()}
    for kind in ("timeToSolution", "roofline", "cubes27", "glue", "spheres", "effects", "precond", "shogi"):
        assert ("doc/performance.md", kind) in kinds, kind
    assert ("doc/architecture.md", "archCompare") in kinds
