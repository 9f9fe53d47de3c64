"""Sphinx extension of the yade-qdem site: the parts of the documentation that
are generated from the package, so that they are never written twice.

``.. qdem-api:: <module>``
    autodoc entries for every public name of the module (its ``__all__``):
    a name added to ``qdem.__all__`` appears in the reference without an edit.
``.. qdem-settings:: <class>``
    the settings table of a class built from documented attributes
    (``QdemEngine``, ``VtkRecorder``, ``QdemMat``): name, default, unit,
    allowed values, meaning.  QdemMat's come from ``QDEM_MATERIAL_FIELDS``
    in ``pkg/material/Material.hpp`` (their unit is a column of that list).  The engine's world settings come from their one
    declaration, ``QDEM_SETTINGS`` in ``pkg/step/Settings.hpp``, through
    ``qdem._core.settings``; the build fails (a warning under ``-W``) when
    the compiled table differs from the header, i.e. when the package the
    site is built from is stale.
``.. bench-table::`` / ``.. bench-figure::``
    the tables and plots of measured figures (Performance, MPI at scale, ...),
    printed or drawn from the benchmark JSON kept in ``bench/logs/``
    (scripts/bench/perf_tables.py, perf_plots.py).
``.. qdem-world-settings::``
    the world settings that are not engine attributes (set on ``World.core``).
``{bench}`FILE:KEY|FORMAT```
    a figure quoted in a sentence, read from kept JSON at build time
    (scripts/bench/doc_figures.py): a missing file or key fails the build.

``publicNames()`` is what the reference must contain; the test
``tests/python/test_doc_site.py`` checks every one of them is in the built site."""
import importlib
import os
import re

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

logger = logging.getLogger(__name__)

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

# The modules of the public API, in the order the reference lists them.  A
# module's public names are its __all__.
PUBLIC_MODULES = ["qdem", "qdem.modes", "qdem.io.render", "qdem.io.plot", "qdem.mpi", "qdem.yade.mpy", "qdem.scenes.shogi"]


def moduleNames(modname):
    """The public names of a module: its __all__ (every public module has one)."""
    mod = importlib.import_module(modname)
    names = getattr(mod, "__all__", None)
    if names is None:
        raise RuntimeError("%s has no __all__: the reference lists a module's __all__" % modname)
    return mod, list(names)


def publicNames():
    """Every public name, qualified (``qdem.addPiece``, ``qdem.modes.viscosityForDamping``)."""
    out = []
    for modname in PUBLIC_MODULES:
        _, names = moduleNames(modname)
        out += ["%s.%s" % (modname, n) for n in names]
    return out


def _kind(obj):
    if isinstance(obj, type):
        return "autoexception" if issubclass(obj, BaseException) else "autoclass"
    if callable(obj):
        return "autofunction"
    return "autodata"


class ApiDirective(SphinxDirective):
    """Autodoc entries for a module's __all__."""
    required_arguments = 1

    def run(self):
        modname = self.arguments[0]
        mod, names = moduleNames(modname)
        lines = []
        for n in names:
            obj = getattr(mod, n, None)
            if obj is None:
                logger.warning("%s.%s cannot be imported: the reference needs YADE's Python modules on "
                               "PYTHONPATH (make doc puts them there) and a built extension "
                               "(make ext)" % (modname, n), location=(self.env.docname, self.lineno))
                continue
            if isinstance(obj, type(os)):
                continue  # a submodule: it has its own section
            lines += [".. %s:: %s.%s" % (_kind(obj), modname, n), ""]
        return _parse(self, lines)


# -- settings tables ------------------------------------------------------------

_UNIT = re.compile(r"\[([A-Za-z][A-Za-z0-9/^ .*-]{0,14})\]")


def _unit(doc):
    """The unit a docstring states, as '[m/s]' (the first such bracket), or
    '-' (a count, a flag, a ratio)."""
    m = _UNIT.search(doc)
    return m.group(1) if m else "-"


def _rule(text):
    """'must lie in [0, 1)' -> 'in [0, 1)'; 'must be > 0 and finite' -> '> 0 and finite'."""
    return re.sub(r"^must (lie |be )?", "", text)


def _allowed(attr):
    """What values an attribute takes, from its own validator or declaration."""
    decl = getattr(attr, "decl", None)
    if decl is not None:
        if decl["kind"] == "choice":
            return "one of " + ", ".join("``'%s'``" % c for c in decl["choices"])
        if decl["kind"] == "bool":
            return "True or False"
        return _rule(decl["rule"])
    if attr.check is None:
        return "any"
    msg = attr.check(object())  # a validator says what it wants of a value it refuses
    return _rule(msg or "any")


def _cell(text):
    return " ".join(str(text).split()).replace("|", "\\|")


def _table(title, rows):
    lines = [".. list-table:: %s" % title, "   :header-rows: 1", "   :widths: 14 10 6 18 52", "",
             "   * - name", "     - default", "     - unit", "     - allowed", "     - meaning"]
    for r in rows:
        lines.append("   * - ``%s``" % r[0])
        lines += ["     - %s" % _cell(c) for c in r[1:]]
    return lines + [""]


def settingsDrift(text=None):
    """Names declared in pkg/step/Settings.hpp (or ``text``, a header's
    contents) against those compiled into qdem._core.settings: a difference
    means the package the site is built from is stale."""
    from qdem import _core
    if text is None:
        text = open(os.path.join(ROOT, "pkg", "step", "Settings.hpp")).read()
    body = text[text.index("#define QDEM_SETTINGS(X)"):]
    declared = re.findall(r"X\(\s*\w+\s*,\s*(\w+)\s*,", body)
    compiled = [d["name"] for d in _core.settings]
    return declared, compiled


class SettingsDirective(SphinxDirective):
    """The attribute table of a class built from qdem.attrs.Attr."""
    required_arguments = 1

    def run(self):
        from qdem.attrs import AttrObject
        path = self.arguments[0]
        modname, clsname = path.rsplit(".", 1)
        cls = getattr(importlib.import_module(modname), clsname)
        declared, compiled = settingsDrift()
        if declared != compiled:
            logger.warning("qdem-settings: the settings compiled into qdem._core (%s) differ from "
                           "QDEM_SETTINGS in pkg/step/Settings.hpp (%s): rebuild the extension "
                           "(cmake --build build --target _core)" % (compiled, declared),
                           location=(self.env.docname, self.lineno))
        rows = []
        for name in AttrObject.attrNames.__func__(cls):
            a = next(vars(k)[name] for k in cls.__mro__ if name in vars(k))
            default = "``%r``" % (a.default,)
            decl = getattr(a, "decl", None) or {}
            unit = (decl["unit"] or "-") if "unit" in decl else _unit(a.doc)
            rows.append((name, default, unit, _allowed(a), decl.get("doc", a.doc) if "unit" in decl else a.doc))
        return _parse(self, _table("Settings of ``%s``" % path, rows))


class WorldSettingsDirective(SphinxDirective):
    """QDEM_SETTINGS entries without an engine name (set on World.core)."""

    def run(self):
        from qdem import _core
        rows = [(d["name"], "``%r``" % (d["default"],), _unit(d["doc"]), _rule(d["rule"]), d["doc"])
                for d in _core.settings if not d["engineName"]]
        return _parse(self, _table("World settings without an engine attribute", rows))


class BenchTableDirective(SphinxDirective):
    """``bench-table:: <kind> <json> [more json]``: a table printed from kept
    benchmark JSON by ``perf_tables.<kind>(json, *more)`` in
    scripts/bench/perf_tables.py (the first file loaded, the others passed as
    paths), so that no figure of a table is copied by hand."""
    required_arguments = 2
    optional_arguments = 4

    def run(self):
        import contextlib
        import io
        import json
        import sys
        sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
        import perf_tables
        kind, paths = self.arguments[0], [os.path.join(ROOT, a) for a in self.arguments[1:]]
        if kind not in perf_tables.GENERATORS:
            logger.warning("bench-table: scripts/bench/perf_tables.py has no table %r; one of %s"
                           % (kind, ", ".join(sorted(perf_tables.GENERATORS))),
                           location=(self.env.docname, self.lineno))
            return []
        missing = [a for a, p in zip(self.arguments[1:], paths) if not os.path.isfile(p)]
        if missing:
            logger.warning("bench-table %s: %s not kept (bench/logs/)" % (kind, ", ".join(missing)),
                           location=(self.env.docname, self.lineno))
            return []
        for p in paths:
            self.env.note_dependency(p)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            perf_tables.GENERATORS[kind](json.load(open(paths[0])), *paths[1:])
        source = "(%s)" % ", ".join("`%s`" % a for a in self.arguments[1:])
        return _parse(self, out.getvalue().splitlines() + ["", source])


class BenchFigureDirective(SphinxDirective):
    """``bench-figure:: <kind> <json> [more json]``: a PNG of the Performance
    page drawn from kept benchmark JSON by scripts/bench/perf_plots.py at
    build time (into ``doc/_generated/``, not kept in git), so that no point
    on a plot is typed by hand; the directive's content is the caption."""
    required_arguments = 2
    optional_arguments = 4
    has_content = True

    def run(self):
        import sys
        sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
        import perf_plots
        kind, paths = self.arguments[0], [os.path.join(ROOT, a) for a in self.arguments[1:]]
        for p in paths:
            self.env.note_dependency(p)
        gen = os.path.join(self.env.srcdir, "_generated")
        os.makedirs(gen, exist_ok=True)
        png = os.path.join(gen, "%s.png" % kind)
        getattr(perf_plots, kind)(png, *paths)
        caption = list(self.content) + ["", "(drawn from %s)" % ", ".join("`%s`" % a for a in self.arguments[1:])]
        lines = [":::{figure} /_generated/%s.png" % kind, ":width: 90%", ""] + caption + [":::"]
        return _parse(self, lines)


def benchRole(name, rawtext, text, lineno, inliner, options=None, content=None):
    """``{bench}`FILE:KEY|OP...```: the figure at KEY of kept JSON FILE
    (bench/logs/), formatted (scripts/bench/doc_figures.py); a spec that
    does not resolve is an error of the build, never a stale figure."""
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
    import doc_figures
    env = inliner.document.settings.env
    try:
        value, path = doc_figures.resolve(text)
    except doc_figures.FigureError as e:
        logger.warning("bench: %s" % e, location=(env.docname, lineno))
        return [nodes.problematic(rawtext, rawtext)], []
    env.note_dependency(path)
    return [nodes.inline(rawtext, value, classes=["bench-figure"])], []


def _parse(directive, lines):
    node = nodes.section()
    node.document = directive.state.document
    nested_parse_with_titles(directive.state, StringList(lines, source="qdemdoc"), node)
    return node.children


def _stripAttributeList(app, what, name, obj, options, lines):
    """A class docstring ends with 'Attributes (default):' and each attribute
    (qdem.attrs.documented, what help() shows); the reference documents the
    attributes one by one and in the settings tables, so the list is cut."""
    if what == "class" and "    Attributes (default):" in [" " * 4 + x.strip() for x in lines]:
        i = next(k for k, x in enumerate(lines) if x.strip() == "Attributes (default):")
        del lines[i:]


_ABS = re.compile(r"(?<![\\|])\|([^|\s][^|]*?)\|(?!_)")


def _plainText(app, what, name, obj, options, lines):
    """The docstrings are YADE-style plain text (what help() shows): an
    absolute value |vt| would read as an undefined reST substitution."""
    for i, x in enumerate(lines):
        lines[i] = _ABS.sub(lambda m: "\\|%s\\|" % m.group(1), x)


def _requireDocstring(app, what, name, obj, options, lines):
    """A public name without a docstring fails the build (under -W): the
    reference is generated from them."""
    if what != "module" and not any(x.strip() for x in lines):
        logger.warning("%s has no docstring: every public name of qdem needs one (the API reference is "
                       "generated from them)" % name, type="qdem", subtype="docstring")


def setup(app):
    app.add_directive("qdem-api", ApiDirective)
    app.add_directive("qdem-settings", SettingsDirective)
    app.add_directive("qdem-world-settings", WorldSettingsDirective)
    app.add_directive("bench-table", BenchTableDirective)
    app.add_directive("bench-figure", BenchFigureDirective)
    app.add_role("bench", benchRole)
    app.connect("autodoc-process-docstring", _stripAttributeList)
    app.connect("autodoc-process-docstring", _plainText)
    app.connect("autodoc-process-docstring", _requireDocstring)
    return {"version": "1", "parallel_read_safe": True}
