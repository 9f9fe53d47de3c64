"""QdemMat: the material of deformable QDEM pieces (defaults: seed paper, Table 1).

Its parameters and laws are declared once, in C++ (``QDEM_MATERIAL_FIELDS`` and
``QDEM_MATERIAL_LAWS`` in pkg/material/Material.hpp, exposed as
``qdem._core.materialFields`` and ``materialLaws``): the attributes, their
defaults, docstrings and checks below are built from that list, and every
value is checked by the core's own rule (``_core.checkMaterialValue``)."""
from . import _core
from .attrs import Attr, AttrObject

# Elastic laws of the elements, Python name -> core value (pkg/element/laws/,
# doc/formulation.md "Material laws"); the first is the default.
LAWS = {d["name"]: d["value"] for d in _core.materialLaws}


class MaterialParameter(Attr):
    """A QdemMat attribute that is a parameter of the compiled material, built
    from its declaration (``decl``: a row of ``qdem._core.materialFields``, or
    the law) and checked by the core when set: a refused value raises the
    core's ValueError, naming the parameter, the value and what it must be."""

    def __init__(self, decl, default, doc):
        self.decl = decl
        super().__init__(default, doc)

    def __set__(self, obj, value):
        obj.__dict__[self.name] = _core.checkMaterialValue(self.name, value)


def _fieldDoc(d):
    unit = " Unit: %s." % d["unit"] if d["unit"] else ""
    return "%s%s Allowed: %s." % (d["doc"], unit, d["rule"][len("must be "):])


def _lawDoc():
    laws = " ".join("'%s'%s: %s" % (d["name"], " (default)" if i == 0 else "", d["doc"])
                    for i, d in enumerate(_core.materialLaws))
    return ("Elastic law of the tetrahedra; all equal Hooke's law with young and poisson at small strain "
            "(doc/formulation.md compares them). " + laws)


def materialParameters(namespace):
    """Adds a MaterialParameter to a class body (``materialParameters(locals())``)
    for each declared material parameter, in declaration order, then ``law``."""
    for d in _core.materialFields:
        namespace[d["name"]] = MaterialParameter(d, d["default"], _fieldDoc(d))
    law = {"name": "law", "kind": "choice", "choices": [d["name"] for d in _core.materialLaws], "unit": ""}
    namespace["law"] = MaterialParameter(law, law["choices"][0], _lawDoc())


class QdemMat(AttrObject):
    """Kelvin-Voigt viscoelastic material of a QDEM piece, plus the contact
    parameters of its surface particles.  Keyword construction as in YADE::

        mat = QdemMat(young=5e8, poisson=0.4, density=700, viscosity=2.5e5)
    """

    materialParameters(locals())
    label = Attr("", "Free text label, as YADE materials have.")

    def __setattr__(self, name, value):
        # The compiled world copies a material when a piece first uses it
        # (mass, stable step, contact constants are derived from it there):
        # a later edit would be silently ignored, so it is refused.
        if self.__dict__.get("_inUse") and name in type(self).attrNames() and name != "label":
            raise ValueError("QdemMat: cannot change %s after addPiece used this material (the pieces keep the "
                             "values they were built with). Make a new QdemMat for new pieces: "
                             "qdem.QdemMat(**dict(mat.dict(), %s=%r))" % (name, name, value))
        object.__setattr__(self, name, value)

    def coreArgs(self):
        """Keyword arguments of the compiled World.addMaterial: every material parameter and the law."""
        return {k: getattr(self, k) for k in type(self).attrNames() if k != "label"}
