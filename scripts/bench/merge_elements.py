"""Merges the QDEM element benchmark and YADE's FEM figure into out/bench/elements.json,
with the ratio of the two measured in the same run."""
import json
import sys

qdem = json.load(open(sys.argv[1]))
try:
    fem = json.load(open(sys.argv[2]))
except (OSError, ValueError) as e:
    fem = {"yade_fem_ns_per_tet_step": None, "error": str(e)}
out = dict(qdem)
out["yade_fem_ns_per_tet_step"] = fem.get("yade_fem_ns_per_tet_step")
out["yade_fem"] = fem
ours = qdem["threads"].get("2", qdem["threads"]["1"])["ns_per_tet_step"]
if out["yade_fem_ns_per_tet_step"]:
    out["yade_fem_over_qdem"] = out["yade_fem_ns_per_tet_step"] / ours
out["target_ns_per_tet_step_2_threads"] = 15.0
print(json.dumps(out, indent=2))
