#!/usr/bin/env python3
"""The files it takes to add a contact kind between pieces, counted, against
what doc/architecture.md says ("Add a contact kind", the number of files in
its first sentence).

The proof is the test-only kind with history, nodeSpringTest
(pkg/phases/NodeSpringKind.cpp): every source file outside tests/ and doc/
that names it is a file its addition touched.  The check fails when that set
is not {its own file, the table's file, the settings' file}, when the table
or the settings hold more than the kind's row and declaration or its switch
line, or when the count differs from the doc's.  Run by ctest (`kindFiles`).

    python3 tests/arch/check_kind_files.py [repository root]
"""
import os
import re
import sys

NAMES = re.compile(r"NodeSpringKind|nodeSpringTest")
WORDS = {"one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8}
SKIP = {"build", "out", "tests", "doc", ".git", "bench", "third_party"}
KIND_FILE = "pkg/phases/NodeSpringKind.cpp"
# File -> the most lines in it that may name the kind: its row (and the
# declaration of its make function) in the table, its switch line.
EDITS = {"pkg/phases/ContactKinds.cpp": 4, "pkg/step/Settings.hpp": 1}


def touched(root):
    """{path: number of lines naming the kind} over the sources outside tests and docs."""
    out = {}
    for dirpath, dirs, files in os.walk(root):
        rel = os.path.relpath(dirpath, root)
        if rel.split(os.sep)[0] in SKIP or "/build" in "/" + rel:
            dirs[:] = []
            continue
        for f in files:
            if not f.endswith((".cpp", ".hpp", ".h", ".py", ".txt", ".cmake")) and f != "Makefile":
                continue
            path = os.path.join(dirpath, f)
            try:
                lines = open(path, encoding="utf-8").read().splitlines()
            except (UnicodeDecodeError, OSError):
                continue
            n = sum(1 for line in lines if NAMES.search(line))
            if n:
                out[os.path.relpath(path, root)] = n
    return out


def docCount(root):
    text = open(os.path.join(root, "doc", "architecture.md"), encoding="utf-8").read()
    m = re.search(r"\*\*Add a contact kind\*\*[^(]*\((\w+) files", text)
    if not m or m.group(1) not in WORDS:
        return None
    return WORDS[m.group(1)]


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__))))
    files = touched(root)
    errors = []
    if KIND_FILE not in files:
        errors.append("%s does not name the kind (or is gone)" % KIND_FILE)
    for path, n in sorted(files.items()):
        if path == KIND_FILE:
            continue
        if path not in EDITS:
            errors.append("%s names the test kind: adding a kind touched a file the doc does not count" % path)
        elif n > EDITS[path]:
            errors.append("%s names the test kind on %d lines (more than its row / switch line: %d)"
                          % (path, n, EDITS[path]))
    stated = docCount(root)
    if stated is None:
        errors.append("doc/architecture.md: no '**Add a contact kind** ... (N files' with N in words")
    elif stated != len(files):
        errors.append("doc/architecture.md says %d files for a kind; adding nodeSpringTest took %d: %s"
                      % (stated, len(files), ", ".join(sorted(files))))
    for e in errors:
        print("kindFiles: " + e)
    if not errors:
        print("kindFiles: a contact kind with history took %d files (%s), as doc/architecture.md says"
              % (len(files), ", ".join(sorted(files))))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
