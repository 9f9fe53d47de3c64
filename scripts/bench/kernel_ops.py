"""Flops and bytes per tet of the element + integration step, the first
counted from the compiled code: the instructions of each elementBlock
(formerly elementBatch) instance (pkg/element/ElementKernel.hpp, compiled in ElementPhase.cpp.o of
the build's libqdemcore.a) disassembled and counted by kind and vector width.

    /usr/bin/python3.11 scripts/bench/kernel_ops.py [--build build] [--tets 165888 --nodes 33507] > ops.json

How the count is made (the kernel's shape, ElementKernel.hpp): one call of
elementBatch handles kLanes = 8 tets; its gather loop runs once per lane
(tet); the arithmetic is one straight-line SIMD pass over the 8 lanes.  So a
packed instruction outside a loop does one operation for each of `width`
tets (zmm: 8, ymm: 4, xmm: 2): per tet it counts width / 8 times; a scalar
instruction inside the gather loop counts once per tet; a scalar one outside
any loop once per 8 tets.  FMA counts 2 flops, add / sub / mul / div / sqrt /
min / max 1.  A build without AVX-512 (AVX2: 4 doubles a register) compiles
the lane loop, and the gather's two halves, as loops of kLanes / 4 trips: a
packed instruction inside a loop does one operation per tet (counted in
`packed_in_lane_loops`).

Outside elementBatch (counted from the source, ElementPhase.cpp and
IntegrationPhase.cpp): the scatter adds 12 force components per tet into the
thread's buffer; integration does ~20 flops per node (sum of buffers,
gravity, v += dt f / m, x += dt v), x nodes per tet.

Bytes per tet: the data the step must move at least once (each array
touched once per step, every reuse from cache): tet data (4 int32 node ids,
9 doubles of the inverse edge matrix, 1 reference volume = 96 B) plus per
node: position read and written (48 B), velocity read and written (48 B),
mass read (8 B), the force buffer written by the element phase and read by
integration (64 B: the buffers hold 4 doubles per node, x y z and a pad that
lets one aligned vector add do a node, NodeGather.hpp) = 168 B per node,
times nodes per tet."""
import argparse
import json
import os
import re
import subprocess
import tempfile

FMA = re.compile(r"^vf(n)?m(add|sub)(sub|add)?\d{3}(p|s)d$")
ONE = re.compile(r"^v(add|sub|mul|div|sqrt|min|max)(p|s)d$")
WIDTH = {"zmm": 8, "ymm": 4, "xmm": 2}
K_LANES = 8
SCATTER_FLOPS_PER_TET = 12
INTEGRATE_FLOPS_PER_NODE = 20
TET_BYTES = 4 * 4 + 9 * 8 + 8
NODE_BYTES = 48 + 48 + 8 + 64


def disassemble(build):
    lib = os.path.join(build, "libqdemcore.a")
    with tempfile.TemporaryDirectory() as d:
        subprocess.run(["ar", "x", os.path.abspath(lib), "ElementPhase.cpp.o"], cwd=d, check=True)
        return subprocess.run(["objdump", "-d", "-C", "--no-show-raw-insn", os.path.join(d, "ElementPhase.cpp.o")],
                              check=True, capture_output=True, text=True).stdout


def functions(asm):
    """{signature: [(address, mnemonic, operands)]} of the elementBatch instances."""
    out, cur = {}, None
    for line in asm.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if m:
            cur = m.group(1) if re.search(r"element(Batch|Block)<", m.group(1)) else None
            if cur:
                out[cur] = []
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
        if cur and m:
            out[cur].append((int(m.group(1), 16), m.group(2), m.group(3)))
    return out


def count(insns):
    loops = []   # (start, end) of backward jumps inside the function
    for addr, mn, ops in insns:
        m = re.match(r"^([0-9a-f]+)\s", ops)
        if mn.startswith("j") and m and int(m.group(1), 16) < addr:
            loops.append((int(m.group(1), 16), addr))
    # An AVX2 build holds the node gather twice (NodeGather.hpp): with plain
    # loads for blocks where no corner is the array's last node, and with
    # masked loads (vmaskmovpd) for the others; one runs per block.  The
    # masked copy's loops are not counted.
    masked = [(a, b) for a, b in loops if any(a <= x <= b and mn == "vmaskmovpd" for x, mn, _ in insns)]
    loops = [lp for lp in loops if lp not in masked]
    per = {"fma": 0.0, "mul": 0.0, "add_sub": 0.0, "other": 0.0}
    raw, lanesLooped = {}, []
    for addr, mn, ops in insns:
        if any(a <= addr <= b for a, b in masked):
            continue
        two = FMA.match(mn)
        one = ONE.match(mn)
        if not (two or one):
            continue
        raw[mn] = raw.get(mn, 0) + 1
        inLoop = any(a <= addr <= b for a, b in loops)
        packed = (two or one).group(0).endswith("pd")
        if packed:
            w = next((v for k, v in WIDTH.items() if "%" + k in ops), 1)
            # A packed instruction inside a loop: on a build without
            # AVX-512 the lane loop (and the gather's halves) are loops that
            # walk the kLanes lanes `w` at a time, K_LANES / w trips, so the
            # instruction does one operation per tet.  (A loop of another
            # trip count would make this wrong: the AVX2 count is checked
            # against the AVX-512 build's, which has no such loop, in
            # doc/dev/performance_notebook.md.)
            times = 1.0 if inLoop else w / K_LANES
            if inLoop:
                lanesLooped.append("%x %s %s" % (addr, mn, ops))
        else:
            times = 1.0 if inLoop else 1.0 / K_LANES
        kind = "fma" if two else ("mul" if one.group(1) == "mul" else
                                  "add_sub" if one.group(1) in ("add", "sub") else "other")
        per[kind] += times
    flops = 2 * per["fma"] + per["mul"] + per["add_sub"] + per["other"]
    return {"per_tet": per, "flops_per_tet": flops, "instructions": raw, "loops": len(loops),
            "packed_in_lane_loops": len(lanesLooped)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--tets", type=int, default=165888)
    ap.add_argument("--nodes", type=int, default=33507)
    a = ap.parse_args()
    nodesPerTet = a.nodes / a.tets
    res = {"source": "scripts/bench/kernel_ops.py on %s/libqdemcore.a" % a.build, "k_lanes": K_LANES,
           "nodes_per_tet": nodesPerTet, "tet_bytes": TET_BYTES, "node_bytes": NODE_BYTES,
           "scatter_flops_per_tet": SCATTER_FLOPS_PER_TET, "integrate_flops_per_node": INTEGRATE_FLOPS_PER_NODE,
           "kernel": {}, "per_tet": {}}
    for sig, insns in functions(disassemble(a.build)).items():
        m = re.search(r"element(?:Batch|Block)<qdem::(\w+), (true|false), (true|false)>", sig)
        if not m:
            continue
        law = {"SaintVenantKirchhoff": "saintVenantKirchhoff", "StableNeoHookean": "stableNeoHookean"}.get(m.group(1))
        if law is None or m.group(3) == "true":      # the step without energy tracking
            continue
        mode = "viscous" if m.group(2) == "true" else "elastic"
        c = count(insns)
        res["kernel"]["%s %s" % (law, mode)] = c
        res["per_tet"]["%s %s" % (law, mode)] = {
            "kernel_flops": c["flops_per_tet"],
            "flops": c["flops_per_tet"] + SCATTER_FLOPS_PER_TET + INTEGRATE_FLOPS_PER_NODE * nodesPerTet,
            "bytes": TET_BYTES + NODE_BYTES * nodesPerTet}
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
