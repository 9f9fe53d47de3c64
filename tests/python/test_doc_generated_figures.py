"""The figures quoted in sentences of the user pages are read from the JSON
kept in bench/logs/ at build time (the ``{bench}`FILE:KEY|OP...``` role of
doc/_ext/qdemdoc.py, scripts/bench/doc_figures.py), never typed:

- every role of the site resolves (a missing file or key fails here and
  fails the site build);
- the figures these pages quote are roles: a figure typed over its role
  (the role gone) fails;
- no sentence quotes a figure by citing its JSON key by hand
  (``mpi.json: model.inputs``): that figure belongs in a role.

Runs in a second: no Sphinx build (test_doc_site.py builds the site)."""
import glob
import os
import re
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))

import doc_figures  # noqa: E402

ROLE = re.compile(r"\{bench\}`([^`]+)`")
# A figure cited by its JSON key in prose: `mpi.json: model.inputs`, `hits.json`: `wall_s`.
KEY_CITATION = re.compile(r"`?[\w.-]+\.json`?:\s*`?[A-Za-z_][\w.\[\]*]*`?")

# Figures each page must quote through a role ("FILE:KEY", the ops aside):
# typing one of them by hand removes its role and fails the test.
QUOTED = {
    "doc/parallel.md": [
        "mpi_equal_to_serial.json:sleep.threads2.dxOverDisp",
        "mpi_equal_to_serial.json:sleep.P*.dxOverDisp",
        "mpi_spheres.json:spheres.drop.P4.perRank",
        "mpi_spheres.json:spheres.clump.P2.perRank",
        "mpi_spheres.json:broadPhases.A.P3.interiorFaceTests[1]",
        "mpi_spheres.json:broadPhases.B.P3.interiorFaceTests[1]",
        "mpi_mpy.json:drop.mpy3ranks.ownedNodes",
        "mpi_mpy.json:drop.mpy4ranks.ownedNodes",
        "mpi_mpy.json:*.mpy*ranks.layerSecondsPerStep",
        "omp_sync_s12_2026-11-24.json:summary.passive.*.*.median_of_rounds",
    ],
    "doc/parallel_scaling.md": [
        "mpi.json:model.inputs.alpha_s",
        "mpi.json:model.inputs.beta_s_per_byte",
        "mpi.json:model.inputs.ns_per_tet",
        "mpi_rerun.json:model.inputs.alpha_s",
        "mpi_rerun.json:model.inputs.ns_per_tet",
        "mpi_partition_512.json:rows[38].partition_seconds",
    ],
    "doc/shogi.md": [
        "shogi_scales_2026-11-24.json:table1_scale",
        "shogi_table1_scale.json:scale",
        "shogi_scales_2026-11-24.json:scales.1.stable_dt_explicit",
        "shogi_scales_2026-11-24.json:scales.1.elastic_dt",
        "shogi_scales_2026-11-24.json:scales.766.first_mode_damping_ratio",
        "shogi_scales_2026-11-24.json:scales.1.first_mode_damping_ratio",
        "shogi_scales_2026-11-24.json:scales.766.explicit_over_implicit",
        "shogi_scales_2026-11-24.json:runs[0].steps",
        "shogi_scales_2026-11-24.json:runs[0].firstHit_s[1]",
        "shogi_scales_2026-11-24.json:runs[3].fallen_s_at_766x[0]",
        "shogi_cost_in_run_2026-11-24.json:runs.*.from_zero_over_warm",
        "shogi_soft.json:runs.two_rooks_mu0.1_soft.firstHit_s[1]",
        "shogi_soft.json:runs.two_rooks_mu0.5_soft.fallen_s",
        "shogi_soft.json:runs.king_pawns_mu0.1_soft.fallen_s[1]",
        "shogi_table1_766.json:runs.two_rooks_mu0.1_table1.stopped_at_step",
        "shogi_table1_766.json:runs.two_rooks_mu0.1_table1.error",
    ],
}


def userPages():
    return sorted(os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "doc", "*.md")))


def roles(page):
    """(line, spec) of every {bench} role of a page."""
    out = []
    for i, line in enumerate(open(os.path.join(ROOT, page), encoding="utf-8"), 1):
        out += [(i, m.group(1)) for m in ROLE.finditer(line)]
    return out


def specKey(spec):
    """'FILE:KEY' of a spec, its ops left out."""
    return spec.split("|")[0].strip()


@pytest.mark.parametrize("page", userPages())
def test_every_quoted_figure_resolves(page):
    """Each role names a kept JSON file and a key it holds."""
    bad = []
    for line, spec in roles(page):
        try:
            doc_figures.resolve(spec)
        except doc_figures.FigureError as e:
            bad.append("%s:%d: %s" % (page, line, e))
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("page", sorted(QUOTED))
def test_the_figures_are_quoted_from_the_json(page):
    """The figures these pages quote are roles, not typed copies."""
    have = {specKey(spec) for _, spec in roles(page)}
    missing = [k for k in QUOTED[page] if k not in have]
    assert not missing, ("%s: these figures are no longer read from their JSON (typed by hand?); quote them "
                         "with {bench}`FILE:KEY|FORMAT`: %s" % (page, missing))


def keyCitations(text):
    """(line, text) of prose citing a figure's JSON key, outside code blocks and roles."""
    out, fenced = [], False
    for i, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            continue
        prose = ROLE.sub("", line)
        out += [(i, m.group(0)) for m in KEY_CITATION.finditer(prose)]
    return out


@pytest.mark.parametrize("page", sorted(QUOTED))
def test_no_figure_cites_its_json_key_by_hand(page):
    found = keyCitations(open(os.path.join(ROOT, page), encoding="utf-8").read())
    assert not found, "%s: figures cited by JSON key in prose (quote them with the {bench} role): %s" % (
        page, found[:5])


def test_the_checks_themselves():
    """A key citation is caught, a role and a file link are not; a spec
    formats as documented; a missing key is an error naming it."""
    text = ("w = 43.1 ns/tet from `mpi.json: model.inputs`.\n"
            "{bench}`mpi.json:model.inputs.ns_per_tet|%.1f` ns, see [`bench/logs/mpi.json`](../bench/logs/mpi.json).\n")
    assert [i for i, _ in keyCitations(text)] == [1]
    data = {"a": {"P2": {"x": 2e-15}, "P3": {"x": 5e-15}}, "n": [1234, 5]}
    assert doc_figures.apply(doc_figures.lookup(data, "a.P*.x"), ["max", "%.0e"], data) == "5e-15"
    assert doc_figures.apply(doc_figures.lookup(data, "n"), ["{:,}"], data) == "1,234, 5"
    assert doc_figures.apply(doc_figures.lookup(data, "n[0]"), ["/@n[1]", "sig2"], data) == "250"
    with pytest.raises(doc_figures.FigureError, match="P4"):
        doc_figures.lookup(data, "a.P4.x")
