"""Materials are declared once, in C++ (QDEM_MATERIAL_FIELDS and QDEM_MATERIAL_LAWS
in pkg/material/Material.hpp), and reach Python from there: each parameter is a
QdemMat attribute with its default and docstring in help(), checked by the core's
own rule with the core's message (no second copy of the rules in Python), and
World.addMaterial takes keywords.  Adding a law touches three source files,
adding a parameter one line (doc/architecture.md, "How to ...")."""
import ast
import math
import os
import pydoc
import re

import numpy as np
import pytest

import qdem
from qdem import _core
from qdem.material import LAWS, MaterialParameter

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FIELDS = [d["name"] for d in _core.materialFields]


def refusedValues(d):
    """Values just outside a parameter's declared range, and non-finite ones."""
    out = [float("nan"), float("inf"), -float("inf")]
    if math.isfinite(d["lo"]):
        out.append(d["lo"] if d["loOpen"] else np.nextafter(d["lo"], -np.inf))
    if math.isfinite(d["hi"]):
        out.append(d["hi"] if d["hiOpen"] else np.nextafter(d["hi"], np.inf))
    return out


def test_every_declared_parameter_is_a_documented_QdemMat_attribute():
    assert FIELDS == ["young", "poisson", "density", "viscosity", "frictionPiece", "frictionWall", "radius",
                      "restitution"]
    assert qdem.QdemMat.attrNames() == FIELDS + ["law", "label"]
    text = pydoc.render_doc(qdem.QdemMat, renderer=pydoc.plaintext)
    m = qdem.QdemMat()
    for d in _core.materialFields:
        a = vars(qdem.QdemMat)[d["name"]]
        assert isinstance(a, MaterialParameter) and a.decl is d
        assert getattr(m, d["name"]) == d["default"]
        # help() lists it with its default, its meaning, unit and allowed values
        assert "%s (= %r)" % (d["name"], d["default"]) in text
        assert d["doc"] in " ".join(a.__doc__.split())
        assert d["rule"][len("must be "):] in a.__doc__
        if d["unit"]:
            assert "Unit: %s." % d["unit"] in a.__doc__
    assert "law (= %r)" % _core.materialLaws[0]["name"] in text


def test_the_core_keeps_the_defaults_QdemMat_shows():
    """A material added with no keyword is the declared defaults: the same
    stable step as one added with QdemMat()'s values spelled out."""
    w = _core.World()
    w.addMaterial()
    w.addMaterial(**qdem.QdemMat().coreArgs())
    nodes, tets = qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)).nodes, qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)).tets
    w.addPiece(nodes, tets, 0)
    a = w.stableDt()["combined"]
    w2 = _core.World()
    w2.addMaterial(**qdem.QdemMat().coreArgs())
    w2.addPiece(nodes, tets, 0)
    assert w2.stableDt()["combined"] == a


@pytest.mark.parametrize("d", _core.materialFields, ids=FIELDS)
def test_every_parameter_is_checked_by_the_core_rule(d):
    name = d["name"]
    for bad in refusedValues(d):
        with pytest.raises(ValueError) as e:
            qdem.QdemMat(**{name: bad})
        assert str(e.value) == "QdemMat: %s=%r is invalid: %s" % (name, bad, d["rule"])
        # the compiled World.addMaterial refuses it with the same words
        with pytest.raises(ValueError) as core:
            _core.World().addMaterial(**{name: bad})
        assert str(core.value) == str(e.value)
    for bad in (True, "1", [d["default"]], 1j):
        with pytest.raises(ValueError, match="%s=.* is invalid: must be a number" % name):
            qdem.QdemMat(**{name: bad})
    # a value inside the range is kept as a float, NumPy numbers too
    m = qdem.QdemMat(**{name: np.float32(d["default"])})
    assert type(getattr(m, name)) is float


def test_every_law_is_accepted_documented_and_reaches_the_core():
    assert list(LAWS) == [d["name"] for d in _core.materialLaws]
    assert [d["value"] for d in _core.materialLaws] == list(range(len(LAWS)))
    doc = qdem.QdemMat.law.__doc__
    for d in _core.materialLaws:
        assert qdem.QdemMat(law=d["name"]).law == d["name"]
        assert "'%s'" % d["name"] in doc and d["doc"] in doc
        _core.World().addMaterial(law=d["name"])
    rule = "must be one of " + ", ".join("'%s'" % n for n in LAWS)
    for bad in ("neoHooke", 0, None):
        with pytest.raises(ValueError) as e:
            qdem.QdemMat(law=bad)
        assert str(e.value) == "QdemMat: law=%r is invalid: %s" % (bad, rule)
        with pytest.raises(ValueError):
            _core.World().addMaterial(law=bad)


def test_addMaterial_takes_keywords_only():
    w = _core.World()
    assert w.addMaterial(young=1e6, law="saintVenantKirchhoff") == 0
    with pytest.raises(TypeError, match="unknown keyword 'youngs'; known: young, poisson"):
        w.addMaterial(youngs=1e6)
    with pytest.raises(TypeError):
        w.addMaterial(5e8, 0.4, 700.0, 2.5e5, 0.1, 0.5, 0.04, 0.5, 0)  # the former positional form


# -- the lists are the single source: what adding a law or a parameter touches --

def _sources():
    for top in ("pkg", "py"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, top)):
            for f in files:
                if f.endswith((".hpp", ".cpp", ".py")):
                    yield os.path.relpath(os.path.join(dirpath, f), ROOT)


def _code(path):
    """A source file without its comments, strings and docstrings: what the
    compiler or interpreter reads as names."""
    text = open(os.path.join(ROOT, path)).read()
    if path.endswith(".py"):
        names = []
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Name):
                names.append(node.id)
            elif isinstance(node, ast.Attribute):
                names.append(node.attr)
            elif isinstance(node, ast.keyword) and node.arg:
                names.append(node.arg)
            elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                names.append(node.name)
        return " ".join(names)
    text = re.sub(r"//[^\n]*|/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r'"(\\.|[^"\\])*"', '""', text)


def test_a_law_is_named_in_three_source_files():
    """Its file in pkg/element/laws/, its line of QDEM_MATERIAL_LAWS and its
    #include in MaterialLaw.hpp (outside comments and strings)."""
    sources = list(_sources())
    for d in _core.materialLaws:
        tag = d["tag"]
        where = {p for p in sources if re.search(r"\b%s\b" % tag, _code(p))}
        includes = {p for p in sources if '#include "laws/%s.hpp"' % tag in open(os.path.join(ROOT, p)).read()}
        assert where | includes == {"pkg/material/Material.hpp", "pkg/element/MaterialLaw.hpp",
                                    "pkg/element/laws/%s.hpp" % tag}, tag


def test_no_parameter_is_named_outside_its_declaration_and_its_users():
    """The validation, the names, the binding and QdemMat go over the list:
    none of them names a parameter."""
    for path in ("pkg/material/Material.cpp", "py/bindings/bind_material.cpp", "py/qdem/material.py"):
        code = _code(path)
        for name in FIELDS:
            assert not re.search(r"\b%s\b" % name, code), (path, name)
    header = _code("pkg/material/Material.hpp")
    for name in FIELDS:
        assert len(re.findall(r"X\(double, %s," % name, header)) == 1, name


def test_the_architecture_page_counts_the_files():
    text = open(os.path.join(ROOT, "doc", "architecture.md")).read()
    law = text[text.index("**Add a material law**"):]
    law = law[:law.index("\n\n")]
    for path in ("pkg/element/laws/", "QDEM_MATERIAL_LAWS", "MaterialLaw.hpp"):
        assert path in law
    assert "three files" in law
    param = text[text.index("**Add a material parameter**"):]
    assert "one `QDEM_MATERIAL_FIELDS` line" in param[:param.index("\n\n")]
