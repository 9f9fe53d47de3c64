#!/usr/bin/env python3
"""No function in pkg/ longer than 150 lines (doc/architecture.md, "Layers").

A function's length is counted from the line of its name to its closing
brace, lambdas inside it included.  The functions in ALLOWED are the contact
kernels still over the limit; any other function over it fails, and so does
an entry of ALLOWED whose function has come under the limit (or is gone):
the list can only shrink.  Run by ctest (`functionLength`).

    python3 tests/arch/check_function_length.py [repository root] [--list N]
"""
import os
import re
import sys

LIMIT = 150

# Contact kernels over the limit, to be split when the contact kinds become
# plug-ins: qualified name -> its length when the limit was set (for the
# record: the check fails on a function leaving the list, not on a length).
ALLOWED = {
}

CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "static_assert",
           "defined", "requires", "noexcept"}
NAME_BEFORE_PAREN = re.compile(r"((?:~?[A-Za-z_]\w*(?:<[^<>()]*>)?::)*(?:operator\s*[^\s(]+|~?[A-Za-z_]\w*))\s*$")


def strip(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == '"' and i > 0 and text[i - 1] == "R" and re.match(r'"[^ ()\\]*\(', text[i:]):
            # raw string R"delim( ... )delim"
            m = re.match(r'"([^ ()\\]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            j = min(n, j + 1)
            # a digit separator (1'000) is no literal
            if c == "'" and i > 0 and text[i - 1].isalnum() and j - i > 3:
                out.append(c)
                i += 1
                continue
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == "#" and (i == 0 or text[:i].rstrip(" \t").endswith("\n") or text[:i].strip() == ""):
            # preprocessor line (with continuations): blanked
            j = i
            while True:
                k = text.find("\n", j)
                if k < 0:
                    k = n
                    break
                if text[k - 1] == "\\":
                    j = k + 1
                    continue
                break
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:k]))
            i = k
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_name(header):
    """The qualified name if `header` (the text before a '{') opens a function body, else None."""
    h = " ".join(header.split())
    # trailing qualifiers, a constructor's initializer list, a trailing return type
    h = re.sub(r"\s*->\s*[^(){}]*$", "", h)
    while True:
        h2 = re.sub(r"\s*\b(const|override|final|noexcept|mutable|volatile|&|&&)\s*$", "", h)
        h2 = re.sub(r"\s*\bnoexcept\s*\([^()]*\)\s*$", "", h2)
        if h2 == h:
            break
        h = h2
    # constructor initializer list: cut at the ':' that follows the parameter list's ')'
    depth, cut = 0, None
    for i, c in enumerate(h):
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth == 0:
                rest = h[i + 1:].lstrip()
                if rest.startswith(":") and not rest.startswith("::"):
                    cut = i + 1
                    break
    if cut is not None:
        h = h[:cut]
    if not h.endswith(")"):
        return None
    depth = 0
    for i in range(len(h) - 1, -1, -1):
        if h[i] == ")":
            depth += 1
        elif h[i] == "(":
            depth -= 1
            if depth == 0:
                before = h[:i]
                break
    else:
        return None
    if before.rstrip().endswith("]") or before.rstrip().endswith(">") and "[" in before:
        return None  # a lambda
    m = NAME_BEFORE_PAREN.search(before)
    if not m:
        return None
    name = re.sub(r"<[^<>()]*>", "", m.group(1)).replace(" ", "")
    last = name.split("::")[-1]
    if last in CONTROL or "=" in before.split(m.group(1))[-1]:
        return None
    if re.search(r"(^|[^=!<>])=\s*[^=]*$", before) and "operator" not in name:
        return None  # an initializer: T x = f(...) {...} is no definition
    return name


def functions(path):
    """(qualified name, first line, last line) of every function body in a file."""
    with open(path, encoding="utf-8") as fh:
        text = strip(fh.read())
    found = []
    scopes = []  # per open brace: None (not a function) or [name, line]
    stmt_start = 0
    in_function = 0
    line_at = [0]
    for k, c in enumerate(text):
        if c == "\n":
            line_at.append(k + 1)

    def line_of(pos):
        lo, hi = 0, len(line_at) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if line_at[mid] <= pos:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1

    qualifiers = []  # class / struct names of the open class scopes
    for i, c in enumerate(text):
        if c == "{":
            header = text[stmt_start:i]
            entry = None
            if in_function == 0:
                m = re.search(r"\b(class|struct|union)\s+(?:\w+\s+)*?([A-Za-z_]\w*)\s*(?:final\s*)?(?::[^;{]*)?$",
                              " ".join(header.split()))
                if m and "(" not in header:
                    entry = ("class", m.group(2))
                else:
                    name = function_name(header)
                    if name:
                        # the name's line: where the parameter list starts
                        at = header.rfind(name.split("::")[-1] + "(")
                        if at < 0:
                            at = header.find(name.split("::")[-1])
                        start = line_of(stmt_start + max(at, 0))
                        qual = "::".join(q for q in qualifiers if q)
                        full = name if "::" in name or not qual else qual + "::" + name
                        entry = ("function", full, start)
                        in_function += 1
            scopes.append(entry)
            if entry and entry[0] == "class":
                qualifiers.append(entry[1])
            stmt_start = i + 1
        elif c == "}":
            entry = scopes.pop() if scopes else None
            if entry and entry[0] == "function":
                in_function -= 1
                found.append((entry[1], entry[2], line_of(i)))
            elif entry and entry[0] == "class":
                qualifiers.pop()
            stmt_start = i + 1
        elif c == ";":
            stmt_start = i + 1
        elif c == ":" and in_function == 0 and re.search(r"\b(public|private|protected)\s*$", text[stmt_start:i]):
            stmt_start = i + 1
    return found


def long_functions(root, limit):
    out = []
    for dirpath, _, files in os.walk(os.path.join(root, "pkg")):
        for f in sorted(files):
            if f.endswith((".hpp", ".cpp", ".h")):
                path = os.path.join(dirpath, f)
                for name, a, b in functions(path):
                    if b - a + 1 > limit:
                        out.append((b - a + 1, name, os.path.relpath(path, root), a))
    return sorted(out, reverse=True)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), "..", ".."))
    if "--list" in sys.argv:
        n = int(sys.argv[sys.argv.index("--list") + 1])
        for length, name, rel, line in long_functions(root, n):
            print(f"{length:5d}  {rel}:{line}  {name}")
        return 0
    bad = []
    seen = {}
    for length, name, rel, line in long_functions(root, LIMIT):
        short = "::".join(name.split("::")[-2:])
        seen[short] = length
        if short not in ALLOWED:
            bad.append(f"{rel}:{line}: {name} has {length} lines (limit {LIMIT}): split it into named steps")
        else:
            print(f"{rel}:{line}: {name}: {length} lines (allowed, a contact kernel)")
    for short in ALLOWED:
        if short not in seen:
            bad.append(f"{short} is at most {LIMIT} lines now (or gone): remove it from ALLOWED in "
                       "tests/arch/check_function_length.py")
    for b in bad:
        print(b)
    if bad:
        return 1
    print(f"every function in pkg/ is at most {LIMIT} lines, but the {len(ALLOWED)} allowed contact kernels")
    return 0


if __name__ == "__main__":
    sys.exit(main())
