"""QdemMat: the material of deformable QDEM pieces (defaults: seed paper, Table 1)."""
from .attrs import Attr, AttrObject, number, positive, nonNegative

_poisson = number(-1.0, 0.5, loOpen=True, hiOpen=True)
_restitution = number(0.0, 1.0, loOpen=True)

# Elastic laws of the elements (pkg/element/laws/, doc/formulation.md "Material laws").
LAWS = {"stableNeoHookean": 0, "saintVenantKirchhoff": 1}


def _law(v):
    return None if isinstance(v, str) and v in LAWS else "must be one of %s" % ", ".join(repr(k) for k in LAWS)


class QdemMat(AttrObject):
    """Kelvin-Voigt viscoelastic material of a QDEM piece, plus the contact
    parameters of its surface particles.  Keyword construction as in YADE::

        mat = QdemMat(young=5e8, poisson=0.4, density=700, viscosity=2.5e5)
    """

    young = Attr(5.0e8, "Young's modulus E [Pa].", positive)
    poisson = Attr(0.4, "Poisson's ratio, in (-1, 0.5).", _poisson)
    density = Attr(700.0, "Mass density [kg/m^3].", positive)
    viscosity = Attr(2.5e5, "Shear viscosity eta [Pa s] of the Kelvin-Voigt dashpot; the viscous "
                            "stress is (eta/mu) times the elastic stress of the strain rate "
                            "(doc/formulation.md). 0 = purely elastic.", nonNegative)
    frictionPiece = Attr(0.1, "Coulomb kinetic friction coefficient against other QDEM pieces.", nonNegative)
    frictionWall = Attr(0.5, "Coulomb kinetic friction coefficient against YADE walls, boxes and facets "
                        "(the smaller of it and tan(frictionAngle) of the body's material acts, as in YADE).",
                        nonNegative)
    radius = Attr(0.04, "Radius of the surface particles [m]: contacts start when a node comes within "
                        "this distance of a wall (2x of another piece's surface). Sets the contact "
                        "stiffness kn = 2 E r (rigid wall).", positive)
    restitution = Attr(0.5, "Normal restitution coefficient of one particle contact, in (0, 1]; "
                            "sets the contact dashpot.", _restitution)
    law = Attr("stableNeoHookean", "Elastic law of the tetrahedra; both equal Hooke's law with young and "
                                   "poisson at small strain. 'stableNeoHookean' (default; Smith, de Goes and "
                                   "Kim 2018): resists compression without softening and pushes an inverted "
                                   "element back. 'saintVenantKirchhoff': the seed paper's law; its "
                                   "compression response peaks at stretch 1/sqrt(3) and an element crushed "
                                   "past it can stay inverted (QdemEngine then stops with an error). "
                                   "doc/formulation.md compares them.", _law)
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
        """Arguments of the compiled World.addMaterial, in order."""
        return (float(self.young), float(self.poisson), float(self.density), float(self.viscosity),
                float(self.frictionPiece), float(self.frictionWall), float(self.radius),
                float(self.restitution), LAWS[self.law])
