"""A figure quoted in a sentence of a user page, read from kept JSON at build
time: the ``{bench}`` role of doc/_ext/qdemdoc.py, e.g.

    the drop on 4 ranks computes {bench}`mpi_spheres.json:spheres.drop.P4.perRank|{:,}` contact-steps

A spec is ``FILE:KEY[|OP...]``:

- FILE: a JSON file under bench/logs/ (or a path from the repository's root
  when it holds a '/');
- KEY: a dotted path (``scales.766.first_mode_damping_ratio``; a key
  that holds dots is found too: ``runs.two_rooks_mu0.1_soft.dt``); ``[i]``
  indexes a list (``runs[0].steps``); a ``*`` in a part takes every
  matching key of a dict (``spheres.drop.P*.dxOverDisp``: a list), a part
  ``*`` every item of a list (the items without the rest of the path
  are left out); a part may be a glob (``[pe][od]*``: pointPolygon and
  edgeEdge);
- OPs, applied left to right: ``flat`` (a list of lists as one list),
  ``min``, ``max``, ``sum``, ``len``, ``abs``, ``inv`` (1/x);
  ``*X`` / ``/X`` / ``+X`` / ``-X`` (X a number or ``@KEY``, another value of
  the same file); then a format: ``%...`` (printf), ``{...}`` (str.format),
  ``sig2`` / ``sig3`` (two or three significant digits, thousands
  separated).  A list is formatted item by item and joined with ', '.
  Without a format a value prints as str() does.

A missing file or key raises FigureError naming it: the site build turns it
into an error (a warning under -W), so a figure never outlives its JSON."""
import fnmatch
import json
import os
import re

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
LOGS = os.path.join(ROOT, "bench", "logs")


class FigureError(Exception):
    """A spec that does not resolve (missing file, key, or a bad op)."""


def path(fileSpec):
    """The JSON file a spec names: under bench/logs/ unless it holds a '/'."""
    return os.path.join(ROOT, fileSpec) if "/" in fileSpec else os.path.join(LOGS, fileSpec)


# a name may hold a glob class ('[pe][od]*': pointPolygon, edgeEdge); '[digits]' is an index
_PART = re.compile(r"((?:[^.\[\]]|\[[^\]\d][^\]]*\])+)|\[(\d+)\]")


def _parts(key):
    """(name, index) parts of a key; a run of names kept joined when a dict
    holds the dotted name ('runs.two_rooks_mu0.1_soft.dt')."""
    return _PART.findall(key)


def lookup(data, key):
    """The value at a dotted key (see the module's docstring)."""
    values, star = [data], False
    parts = _parts(key)
    while parts:
        name, index = parts.pop(0)
        # a key holding dots (a run named 'two_rooks_mu0.1_soft'): join the next parts while it is longer
        while (name and "*" not in name and parts and parts[0][0] and
               any(isinstance(v, dict) and name not in v and any(k.startswith(name + ".") for k in v)
                   for v in values)):
            name += "." + parts.pop(0)[0]
        nxt = []
        for v in values:
            if index:
                if not isinstance(v, list) or int(index) >= len(v):
                    raise FigureError("no item [%s] at %r" % (index, key))
                nxt.append(v[int(index)])
            elif name == "*" and isinstance(v, list):
                nxt += v
                star = True
            elif "*" in name:
                if not isinstance(v, dict):
                    raise FigureError("%r: a '*' needs a dict" % key)
                hits = sorted((k for k in v if fnmatch.fnmatchcase(k, name)), key=_natural)
                if not hits:
                    if star:
                        continue  # after a '*', a dict without a match is left out too
                    raise FigureError("no key matches %r in %r" % (name, key))
                nxt += [v[k] for k in hits]
                star = True
            else:
                if not isinstance(v, dict) or name not in v:
                    if star:
                        continue  # after a '*', the items without the rest of the path are left out
                    raise FigureError("no key %r (of %r)" % (name, key))
                nxt.append(v[name])
        if not nxt:
            raise FigureError("nothing matches %r" % key)
        values = nxt
    return values if star else values[0]


def _natural(k):
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", k)]


def sig(v, digits):
    """`digits` significant digits, thousands separated: 45,100, 18.3, 0.857."""
    r = float("%.*g" % (digits, v))
    if abs(r) >= 1000:
        return "{:,.0f}".format(r)
    if abs(r) >= 10 ** (digits - 1):
        return "%.0f" % r
    return "%.*g" % (digits, r)


def _format(v, op):
    if op.startswith("%"):
        return op % v
    if op.startswith("{"):
        return op.format(v)
    return sig(v, int(op[3:]))


_ARITH = {"*": lambda a, b: a * b, "/": lambda a, b: a / b, "+": lambda a, b: a + b, "-": lambda a, b: a - b}
_REDUCE = {"min": min, "max": max, "sum": sum, "len": len}


def apply(value, ops, data):
    for op in ops:
        if op == "flat":
            value = [y for x in value for y in (x if isinstance(x, list) else [x])]
        elif op in _REDUCE:
            value = _REDUCE[op](value)
        elif op in ("abs", "inv"):
            f = abs if op == "abs" else (lambda x: 1.0 / x)
            value = [f(x) for x in value] if isinstance(value, list) else f(value)
        elif op[:1] in _ARITH and len(op) > 1:
            b = lookup(data, op[2:]) if op[1] == "@" else float(op[1:])
            f = _ARITH[op[0]]
            value = [f(x, b) for x in value] if isinstance(value, list) else f(value, b)
        elif op.startswith(("%", "{")) or re.fullmatch(r"sig\d", op):
            if isinstance(value, list):
                return ", ".join(_format(x, op) for x in value)
            return _format(value, op)
        else:
            raise FigureError("unknown op %r (flat, min, max, sum, len, abs, inv, *X, /X, +X, -X, %%..., {...}, sigN)" % op)
    return ", ".join(map(str, value)) if isinstance(value, list) else str(value)


def resolve(spec):
    """(text, json path) of a spec ``FILE:KEY[|OP...]``."""
    if ":" not in spec:
        raise FigureError("%r: a figure is FILE:KEY[|OP...]" % spec)
    fileSpec, rest = spec.split(":", 1)
    key, *ops = [x.strip() for x in rest.split("|")]
    p = path(fileSpec.strip())
    if not os.path.isfile(p):
        raise FigureError("%s is not kept (bench/logs/)" % os.path.relpath(p, ROOT))
    with open(p) as f:
        data = json.load(f)
    try:
        return apply(lookup(data, key), ops, data), p
    except (TypeError, ValueError, ZeroDivisionError) as e:
        raise FigureError("%r: %s" % (spec, e))
