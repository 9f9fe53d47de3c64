#!/usr/bin/env python3
"""The include layers of the C++ core (doc/architecture.md, "Layers").

Each folder of pkg/ is one layer; a file may include headers of its own
folder and of the folders listed below it in LAYERS, never of a folder
above it or beside it.  Run by ctest (`layering`); prints every include
that breaks the rule, with the file, the line and the rule, and exits 1.

    python3 tests/arch/check_layers.py [repository root]
"""
import os
import re
import sys

# Lowest first.  Each folder may include the folders it lists (and their
# own allowed folders are not implied: every edge is written out, so that
# the table reads as the rule).
LAYERS = [
    ("core", []),
    ("mesh", ["core"]),
    ("material", ["core"]),
    ("element", ["core", "material"]),
    ("contact", ["core", "mesh", "material", "element"]),
    ("parallel", ["core", "mesh", "material", "element", "contact"]),
    ("step", ["core", "mesh", "material", "element", "contact", "parallel"]),
    ("phases", ["core", "mesh", "material", "element", "contact", "parallel", "step"]),
    ("world", ["core", "mesh", "material", "element", "contact", "parallel", "step", "phases"]),
]

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def layer_rank():
    return {name: i for i, (name, _) in enumerate(LAYERS)}


def violations(root):
    """(file, line, text, rule) for every include of pkg/ that breaks the layers."""
    pkg = os.path.join(root, "pkg")
    allowed = {name: set(below) | {name} for name, below in LAYERS}
    rank = layer_rank()
    out = []
    for dirpath, _, files in os.walk(pkg):
        for f in sorted(files):
            if not f.endswith((".hpp", ".cpp", ".h")):
                continue
            path = os.path.join(dirpath, f)
            rel = os.path.relpath(path, root)
            layer = os.path.relpath(path, pkg).split(os.sep)[0]
            if layer not in allowed:
                out.append((rel, 0, "", f"pkg/{layer} is no layer: add it to LAYERS in tests/arch/check_layers.py "
                                        "and to doc/architecture.md"))
                continue
            with open(path, encoding="utf-8") as fh:
                for lineno, line in enumerate(fh, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    target = os.path.normpath(os.path.join(dirpath, m.group(1)))
                    if not os.path.exists(target):
                        # "world/World.hpp" style: relative to pkg/
                        alt = os.path.normpath(os.path.join(pkg, m.group(1)))
                        target = alt if os.path.exists(alt) else target
                    trel = os.path.relpath(target, pkg)
                    if trel.startswith(".."):
                        out.append((rel, lineno, line.strip(), "includes a file outside pkg/: the core sees "
                                                               "no Python, YADE or test code"))
                        continue
                    tlayer = trel.split(os.sep)[0]
                    if tlayer in allowed[layer]:
                        continue
                    if tlayer not in rank:
                        why = f"pkg/{tlayer} is no layer"
                    elif rank[tlayer] > rank[layer]:
                        why = f"pkg/{layer} may not include pkg/{tlayer}, a layer above it"
                    else:
                        why = f"pkg/{layer} may not include pkg/{tlayer}, a layer beside it"
                    out.append((rel, lineno, line.strip(),
                                f"{why} (pkg/{layer} may include: {', '.join(sorted(allowed[layer]))})"))
    return out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
    root = os.path.abspath(root)
    bad = violations(root)
    for rel, lineno, text, why in bad:
        print(f"{rel}:{lineno}: {text}\n    {why}")
    order = " < ".join(name for name, _ in LAYERS)
    if bad:
        print(f"{len(bad)} include(s) run up or across the layers {order}")
        return 1
    print(f"layers hold: {order}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
