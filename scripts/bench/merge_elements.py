"""Merges the QDEM element benchmark (bench_elements JSON) and YADE's FEM figure
into out/bench/elements.json, with the ratio of the two measured in the same
run: ours is the default law (Stable Neo-Hookean), viscous (Table 1), on the
165,888-tet mesh and 2 threads, median of the clean runs (of all runs, said
so, when every run was taken on a busy machine).

    merge_elements.py elements_qdem.json yade_fem.json > elements.json"""
import json
import sys


def ours(qdem, law="stableNeoHookean", mode="viscous", threads=2, tets=165888):
    """(ns/tet/step for the whole step, which runs it came from) of one case."""
    for mesh in qdem["meshes"]:
        if mesh["tets"] != tets:
            continue
        for c in mesh["cases"]:
            if (c["law"], c["mode"], c["threads"]) == (law, mode, threads):
                if c["clean"]["whole_step"]:
                    return c["clean"]["whole_step"]["median"], "clean runs"
                return c["all"]["whole_step"]["median"], "all runs (every run busy)"
    return None, "not measured"


def main():
    qdem = json.load(open(sys.argv[1]))
    try:
        fem = json.load(open(sys.argv[2]))
    except (OSError, ValueError) as e:
        fem = {"yade_fem_ns_per_tet_step": None, "error": str(e)}
    out = dict(qdem)
    out["yade_fem_ns_per_tet_step"] = fem.get("yade_fem_ns_per_tet_step")
    out["yade_fem"] = fem
    threads = 2 if any(c["threads"] == 2 for m in qdem["meshes"] for c in m["cases"]) else 1
    mine, source = ours(qdem, threads=threads)
    out["qdem_ns_per_tet_step"] = {"value": mine, "threads": threads, "from": source,
                                   "case": "stableNeoHookean, viscous, 165,888 tets, whole step, median"}
    out["yade_fem_over_qdem"] = (out["yade_fem_ns_per_tet_step"] / mine
                                 if out["yade_fem_ns_per_tet_step"] and mine else None)
    # Issue 16 target 1 (element + integration, 2 threads; 1 thread in brackets).
    out["targets"] = {"element_integrate_ns_per_tet_step_2_threads": 5.0,
                      "element_integrate_ns_per_tet_step_1_thread": 9.0,
                      "speedup_1_to_2_threads": 1.8}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
