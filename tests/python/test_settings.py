"""Each world setting is declared once (pkg/step/Settings.hpp) and reaches
Python from there (issue 13): the core World property with its check and
docstring, the QdemEngine attribute with its default in help(), and no copy
in the engine - the engine reads and writes the world's setting."""
import pydoc

import pytest

import qdem
from qdem import _core


def engineSettings():
    return [d for d in _core.settings if d["engineName"]]


def test_every_declared_setting_is_a_documented_engine_attribute(scene):
    e = qdem.QdemEngine()
    text = pydoc.render_doc(qdem.QdemEngine, renderer=pydoc.plaintext)
    fresh = _core.World()
    assert len(engineSettings()) >= 14
    for d in engineSettings():
        name = d["engineName"]
        assert name in e.dict()
        shown = d["choices"][d["default"]] if d["kind"] == "choice" else d["default"]
        # help() lists it with its default, and a fresh world starts from it
        assert "%s (= %r)" % (name, shown) in text, name
        assert getattr(fresh, d["name"]) == d["default"], name
        assert getattr(e, name) == shown, name
        # the core property carries the same docstring and the allowed values
        doc = getattr(_core.World, d["name"]).__doc__
        assert d["doc"][:40] in doc and d["rule"] in doc, name


def test_engine_reads_and_writes_the_world_directly(scene):
    e = qdem.QdemEngine(friction=False, frictionModel="regularized", sleepVelocity=1e-3)
    core = qdem.defaultWorld().core
    assert (core.frictionOn, core.frictionModel, core.sleepVelocity) == (False, 1, 1e-3)
    core.frictionOn = True        # changed on the world: the engine shows it
    core.broadPhase = 3
    assert e.friction is True and e.broadPhase == "C"
    e.damping = 0.2               # changed on the engine: the world has it at once
    assert core.localDamping == 0.2
    assert e.dict()["damping"] == 0.2


@pytest.mark.parametrize("name,value,rule", [
    ("damping", 1.0, r"must lie in \[0, 1\)"),
    ("frictionRegVelocity", 0.0, "must be > 0"),
    ("sleepTime", -1, "must be >= 0"),
    ("edgeFadeAngle", 2.0, r"must lie in \[1e-06, 1.5708\]: an angle in radians"),
    # A tester's case: 30 (degrees meant) was taken as 30 rad, a cosine's wrap
    # to ~81 degrees; 6.2 or 12.57 ("above pi: none", the help said) were the default.
    ("edgeFeatureAngle", 30, r"must lie in \[0, 3.14159\]: an angle in radians \(30 degrees is 0.5236\)"),
    ("edgeFeatureAngle", 6.2, r"must lie in \[0, 3.14159\]"),
    ("broadPhase", "D", "must be one of"),
    ("frictionModel", "coulomb", "must be one of"),
])
def test_bad_values_are_refused_naming_the_setting_and_the_rule(scene, name, value, rule):
    e = qdem.QdemEngine()
    before = getattr(e, name)
    with pytest.raises(ValueError, match="QdemEngine: %s=.* is invalid: %s" % (name, rule)):
        setattr(e, name, value)
    assert getattr(e, name) == before   # nothing changed


def test_core_refuses_bad_values_too(scene):
    core = qdem.defaultWorld().core
    with pytest.raises(ValueError, match=r"World.verletSkin=-0.1 is invalid: must be >= 0"):
        core.verletSkin = -0.1
    with pytest.raises(ValueError, match=r"World.frictionModel=2 is invalid: must be one of 0 \('spring'\), "
                                         r"1 \('regularized'\)"):
        core.frictionModel = 2
    with pytest.raises(ValueError, match="World.localDamping=nan is invalid"):
        core.localDamping = float("nan")


def test_contact_kinds_come_from_the_table_with_their_switches(scene):
    """The piece-piece contact kinds are rows of one table (pkg/phases/ContactKind.hpp);
    each row's switch is a declared setting, hence an engine attribute."""
    kinds = {k["name"]: k for k in _core.contactKinds}
    assert list(kinds)[:2] == ["pointPolygon", "edgeEdge"]
    byMember = {d["name"]: d for d in _core.settings}
    e = qdem.QdemEngine()
    for k in kinds.values():
        assert k["registers"] and k["history"]
        d = byMember[k["switch"]]
        assert d["kind"] == "bool" and d["engineName"] in e.dict()
        # the switch turns the kind off: its counter is reported either way
        assert k["name"] in qdem.defaultWorld().core.contactCounts
