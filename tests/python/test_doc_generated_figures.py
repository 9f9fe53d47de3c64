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
    "doc/performance.md": [
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.cg_iterations_per_step.old",
        "time_to_solution_2026-11-28.json:scenes.*.levers.*.runs.*.load1",
        "time_to_solution_2026-11-28.json:scenes.*.levers.*.runs.*.other_cores",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.projected_full_run.simulated_s",
        "time_to_solution_2026-11-28.json:scenes.king_and_pawns_real_size.projected_full_run.simulated_s",
        "time_to_solution_2026-11-28.json:scenes.forty_front_766x.projected_full_run.simulated_s",
        "time_to_solution_2026-11-28.json:full_runs.forty_real_size_mu0.1.simulated_s",
        "time_to_solution_2026-11-28.json:full_runs.forty_real_size_mu0.5.simulated_s",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.projected_full_run.awake_factor",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.pieces_awake",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.cpu_s_per_simulated_s.old",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.cpu_s_per_simulated_s.old",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.cg_iterations_per_step.old",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.cpu_s_per_simulated_s.new",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.summary.cpu_ms_per_step.median",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.dt",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.jacobi.summary.cpu_ms_per_step.median",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.jacobi.phase_shares_median.viscousSolve",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.phase_shares_median.viscousSolve",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.phase_shares_median.obstacles",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.phase_shares_median.[pe][od]*",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.phase_shares_median.broadPhase",
        "time_to_solution_2026-11-28.json:scenes.forty_front_real_size.levers.cholesky.phase_shares_median.[ei][ln]*",
        "time_to_solution_2026-11-28.json:scenes.king_and_pawns_766x.cg_iterations_per_step.old",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_766x.cg_iterations_per_step.old",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_766x.cpu_s_per_simulated_s.old",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_766x.cpu_s_per_simulated_s.new",
        "time_to_solution_2026-11-28.json:scenes.king_and_pawns_766x.cpu_s_per_simulated_s.old",
        "time_to_solution_2026-11-28.json:scenes.king_and_pawns_766x.cpu_s_per_simulated_s.new",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:simulated_s",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:fallen_s[1]",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:steps",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:cg_iterations_per_step",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:wall_s",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:cpu_s",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:load1.min",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:load1.max",
        "time_to_solution_full_two_rooks_real_size_mu0.1.json:load1.median",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.steps",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.projected_full_run.wall_s",
        "time_to_solution_2026-11-28.json:scenes.two_rooks_real_size.projected_full_run.cpu_s",
        "time_to_solution_2026-11-28.json:full_runs.forty_real_size_mu0.1.projected_cpu_s",
        "time_to_solution_2026-11-28.json:full_runs.forty_real_size_mu0.5.projected_cpu_s",
        "time_to_solution_2026-11-28.json:full_runs.forty_real_size_mu0.1.projected_wall_s",
        "roofline_2026-11-24.json:results[0].on_cpu.all.median",
        "roofline_2026-11-24.json:results[1].on_cpu.all.median",
        "roofline_2026-11-24.json:results[3].on_cpu.all.median",
        "roofline_2026-11-24.json:results[3].on_cpu.all.max",
        "effects_2026-11-28.json:effects.*.runs.*.*.other_cores",
        "effects_2026-11-28.json:effects.viscosity.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.viscosity.paired.zero_over_off.cpu.min",
        "effects_2026-11-28.json:effects.viscosity.paired.zero_over_off.cpu.max",
        "effects_2026-11-28.json:effects.friction.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.edgeEdge.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.gravity.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.yadeSpheres.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.contacts.paired.zero_over_off.cpu.median",
        "effects_2026-11-28.json:effects.contacts.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.pointPolygon.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.yadeSpheres.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.energy.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.viscosity.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.edgeEdge.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.friction.paired.on_over_off.cpu.median",
        "effects_2026-11-28.json:effects.*.paired.*.qdem.min",
        "effects_2026-11-28.json:effects.*.paired.*.qdem.max",
        "effects_2026-11-28.json:effects.gravity.qdem.all.off.min",
        "effects_2026-11-28.json:effects.friction.qdem.all.off.min",
        "effects_2026-11-28.json:effects.friction.all.off.min",
        "effects_2026-11-28.json:effects.yadeSpheresAllPairs.paired.zero_over_off.cpu.median",
        "precond_two_rooks_1thread.json:dt",
        "precond_two_rooks_1thread.json:runs.*.*.load1",
        "precond_two_rooks_2threads.json:runs.*.*.load1",
        "precond_two_rooks_2threads.json:runs.*.*.other_cores",
        "precond_two_rooks_1thread.json:runs.*.*.other_cores",
        "precond_two_rooks_1thread.json:summary.cholesky.ms_per_step.median",
        "precond_two_rooks_1thread.json:summary.jacobi.cpu_ms_per_step.median",
        "precond_two_rooks_2threads.json:summary.jacobi.ms_per_step.median",
        "precond_two_rooks_1thread.json:summary.jacobi.cg_iterations_per_step.median",
        "precond_two_rooks_2threads.json:summary.jacobi.cg_iterations_per_step.median",
        "shogi_2026-11-24.json:scenes.forty_2threads.all.ms_per_step.median",
        "shogi_2026-11-24.json:scenes.two_rooks_2threads.all.ms_per_step.median",
        "shogi_2026-11-24.json:scenes.*.runs.*.load1",
        "shogi_2026-11-24.json:scenes.two_rooks_2threads.first_hit_step[0]",
        "shogi_2026-11-24.json:scenes.king_pawns_2threads.first_hit_step",
        "shogi_2026-11-24.json:scenes.forty_2threads.first_hit_step[0]",
        "shogi_2026-11-24.json:scenes.forty_2threads.tets",
        "shogi_2026-11-24.json:scenes.forty_2threads.all.ms_per_step_on_cpu.median",
        "shogi_scales_2026-11-24.json:runs[0].firstHit_s_at_766x[1]",
        "shogi_table1_766.json:runs.two_rooks_mu0.1_table1.stopped_at_step",
        "surface_spin_2026-11-28.json:surface_nodes",
        "surface_spin_2026-11-28.json:rounds",
        "surface_spin_2026-11-28.json:steps",
        "surface_spin_2026-11-28.json:load1.before",
        "surface_spin_2026-11-28.json:load1.after",
        "surface_spin_2026-11-28.json:ns_per_node_step_on_cpu.median",
        "surface_spin_2026-11-28.json:ns_per_node_step_on_cpu.min",
        "surface_spin_2026-11-28.json:share_of_point_polygon_edge_edge.median",
        "surface_spin_2026-11-28.json:ns_per_node_step.median",
        "surface_spin_2026-11-28.json:ns_per_node_step.min",
    ],
    "doc/spheres.md": [
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x1.rolling_ratio",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x1.friction_falls",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x1.drift_over_kinetic",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x1.dt_over_pwave",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x0.5.drift_over_kinetic",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0.5_x0.25.drift_over_kinetic",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0_x1.drift_over_kinetic",
        "spheres_oblique_ledger.json:runs.dt0.5_mu0_x0.5.drift_over_kinetic",
        "spheres_2026-11-28_quiet.json:per_listed_sphere_us",
        "spheres_2026-11-28_quiet.json:fixed_cost_ms_per_step",
    ],
    "doc/architecture.md": [
        "arch_compare_phases_stableids.json:scenes.cubes27.checkpoints",
        "arch_compare_phases_stableids.json:scenes.cubes27.counts.new_1.pointPolygon",
        "arch_compare_phases_stableids.json:scenes.cubes27.counts.new_1.edgeEdge",
        "arch_compare_phases_stableids.json:scenes.cubes27.counts.new_1.verletRebuilds",
        "arch_compare_phases_stableids.json:scenes.shogi.checkpoints",
        "arch_compare_phases_stableids.json:scenes.spheres.checkpoints",
        "arch_compare_phases_stableids.json:scenes.restart.licence_ratio",
        "arch_compare_phases_stableids.json:scenes.restart.run_to_run_ratio",
        "arch_old_vs_new.json:summary.all.rows[0].old.n",
        "arch_old_vs_new.json:summary.all.rows.*.paired_ratio_median",
        "arch_old_vs_new.json:summary.all.rows[22].paired_ratio_median",
        "arch_old_vs_new.json:summary.all.rows[22].sign_test_p",
        "arch_cubes27_quiet.json:summary.1 threads ours step_ms.ratio_median",
        "arch_cubes27_quiet.json:summary.1 threads ours step_ms.ratio_min",
        "arch_cubes27_quiet.json:summary.2 threads ours step_ms.ratio_median",
        "arch_cubes27_quiet.json:summary.2 threads ours step_ms.ratio_min",
        "arch_instructions.json:runs[0].irPerStep",
        "arch_instructions.json:runs[1].irPerStep",
        "arch_instructions.json:runs[2].irPerStep",
        "arch_instructions.json:runs[2].phaseIr.ObstaclePhase",
        "arch_instructions.json:runs[2].phaseIr.PieceContactPhase",
        "arch_instructions.json:runs[2].phaseIr.IntegrationPhase",
        "arch_instructions.json:runs[2].phaseIr.ElementPhase",
        "arch_cubes27_quiet_after_ratios.json:rounds",
        "arch_cubes27_quiet_after_ratios.json:load1.min",
        "arch_cubes27_quiet_after_ratios.json:load1.max",
        "arch_cubes27_quiet_after_ratios.json:others_cores_max",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.step_ms.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.2.ours.step_ms.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.step_ms.ratio_of_minima",
        "arch_cubes27_quiet_after_ratios.json:threads.2.ours.step_ms.ratio_of_minima",
        "arch_cubes27_quiet_after_ratios.json:threads.1.C.step_ms.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.2.C.step_ms.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.elements.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.pointPolygon.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.pointPolygon.ratio_of_minima",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.broadPhase.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.obstacles.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.integrate.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.integrate.new_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.integrate.old_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.edgeEdge.paired_ratio_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.edgeEdge.new_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.edgeEdge.old_median",
        "arch_cubes27_quiet_after_ratios.json:threads.1.ours.step_ms.new_median",
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
    # a glob class in a part; a '*' over a dict that has no match is left out, not an error
    shares = {"s": {"pointPolygon": 0.25, "edgeEdge": 0.5, "elements": 4.0}, "r": {"a": {"x": 1}, "b": {}}}
    assert doc_figures.apply(doc_figures.lookup(shares, "s.[pe][od]*"), ["sum"], shares) == "0.75"
    assert doc_figures.lookup(shares, "r.*.x*") == [1]
    with pytest.raises(doc_figures.FigureError, match="P4"):
        doc_figures.lookup(data, "a.P4.x")
