"""Shuffle, load and arithmetic instructions of one compiled element kernel
instance, counted from the disassembly (objdump -d) of a binary: for
comparing builds of the gather (NodeGather.hpp) by what the compiler emitted.

    /usr/bin/python3.11 scripts/bench/arch/shuffle_count.py BINARY [BINARY ...] \\
        [--function 'elementBlock<qdem::SaintVenantKirchhoff, true, false'] [--out counts.json]

For each binary: the first function whose demangled name contains
--function (the SVK viscous instance without energy by default: the one the
benchmark's "SVK viscous" case runs), its instruction count, and counts per
class, each split by register width (zmm 8 lanes, ymm 4, xmm or scalar):
  shuffle   vperm*, vshuf*, vunpck*, vinsert*, vextract*, vpermi2/t2
  broadcast vbroadcast* (a load, no shuffle unit where the source is memory)
  fma, mul, add (add and sub), move (vmov*: loads, stores, register copies)
and every mnemonic's count.  Only what sits inside the function is counted:
code inlined into its callers (the force scatter, inlined into the element
phase's loop) is not."""
import argparse
import collections
import json
import re
import subprocess
import sys

CLASSES = [("shuffle", re.compile(r"^v(perm|shuf|unpck|insert|extract)")),
           ("broadcast", re.compile(r"^vbroadcast")),
           ("fma", re.compile(r"^vf(n)?m(add|sub)")),
           ("mul", re.compile(r"^vmul")),
           ("add", re.compile(r"^v(add|sub)")),
           ("move", re.compile(r"^vmov"))]


def width(operands):
    for w in ("zmm", "ymm", "xmm"):
        if "%" + w in operands:
            return w
    return "other"


def count(binary, function):
    dis = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", binary], capture_output=True, text=True,
                         check=True).stdout
    body, name, inside = [], None, False
    for line in dis.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if m:
            if inside:
                break
            inside = function in m.group(1)
            name = m.group(1) if inside else name
            continue
        if inside and "\t" in line:
            parts = line.split("\t")
            if len(parts) >= 2:
                ins = parts[1].split(None, 1)
                body.append((ins[0], ins[1] if len(ins) > 1 else ""))
    if not body:
        sys.exit("shuffle_count: no function containing %r in %s" % (function, binary))
    classes = {c: collections.Counter() for c, _ in CLASSES}
    for mnem, ops in body:
        for c, rx in CLASSES:
            if rx.match(mnem):
                classes[c][width(ops)] += 1
                break
    return {"binary": binary, "function": name, "instructions": len(body),
            "classes": {c: dict(v) for c, v in classes.items()},
            "mnemonics": dict(collections.Counter(m for m, _ in body).most_common())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binaries", nargs="+")
    ap.add_argument("--function", default="elementBlock<qdem::SaintVenantKirchhoff, true, false")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    res = [count(b, a.function) for b in a.binaries]
    for r in res:
        print("%s: %s: %d instructions; shuffles %s; broadcasts %s" % (
            r["binary"], r["function"][:80], r["instructions"], r["classes"]["shuffle"], r["classes"]["broadcast"]),
            file=sys.stderr)
    text = json.dumps(res, indent=1)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    else:
        print(text)


if __name__ == "__main__":
    main()
