"""YADE-style attribute classes: keyword construction, a docstring per attribute,
and a clear error for an unknown keyword (YADE users expect ``FrictMat(young=...)``)."""
import numbers

import numpy as np

from . import _core


class Attr:
    """One documented attribute: default value, docstring, optional validator
    (``check(value)`` returns None or what the value must be) and conversion
    applied to an accepted value (``convert``: e.g. int, so that a NumPy
    integer is kept as a plain int, which json and YADE's saves take).  A
    validator made by ``integer``, ``number`` or ``boolean`` brings its own
    conversion."""

    def __init__(self, default, doc, check=None, convert=None):
        self.default, self.doc, self.check = default, doc, check
        self.convert = convert if convert is not None else getattr(check, "convert", None)
        self.name = None

    def __set_name__(self, owner, name):
        self.name = name
        self.__doc__ = self.doc

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        return obj.__dict__.get(self.name, self.default)

    def __set__(self, obj, value):
        if self.check is not None:
            msg = self.check(value)
            if msg:
                raise ValueError("%s: %s=%r is invalid: %s" % (type(obj).__name__, self.name, value, msg))
            if self.convert is not None:
                value = self.convert(value)
        obj.__dict__[self.name] = value


def _showDefault(v):
    return repr(v)


def documented(cls):
    """Appends the attribute list, each with its default, to the class docstring
    (what help() shows first, as YADE's help lists attributes with defaults)."""
    rows = []
    for name in AttrObject.attrNames.__func__(cls):
        a = None
        for klass in cls.__mro__:
            if isinstance(vars(klass).get(name), Attr):
                a = vars(klass)[name]
                break
        rows.append("    %s (= %s)\n        %s" % (name, _showDefault(a.default), a.doc))
    cls.__doc__ = (cls.__doc__ or "").rstrip() + "\n\n    Attributes (default):\n\n" + "\n".join(rows) + "\n"
    return cls


class AttrObject:
    """Base class: ``Cls(a=1, b=2)`` sets documented attributes, rejects unknown ones."""

    @classmethod
    def attrNames(cls):
        names = []
        for klass in reversed(cls.__mro__):
            for k, v in vars(klass).items():
                if isinstance(v, Attr) and k not in names:
                    names.append(k)
        return names

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        documented(cls)

    def __init__(self, **kw):
        known = self.attrNames()
        for k, v in kw.items():
            if k not in known:
                raise TypeError("%s: unknown keyword %r; known attributes: %s"
                                % (type(self).__name__, k, ", ".join(known)))
            setattr(self, k, v)

    def dict(self):
        """All attributes as a plain dict (like YADE's ``Serializable.dict()``)."""
        return {k: getattr(self, k) for k in self.attrNames()}

    def __repr__(self):
        return "%s(%s)" % (type(self).__name__, ", ".join("%s=%r" % kv for kv in self.dict().items()))


def _isnum(v):
    """A finite real number: int, float or a NumPy scalar of them; not a bool,
    a string (float('1e6') would pass), a complex number or an array."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        return False
    f = float(v)
    return f == f and abs(f) != float("inf")


def _isint(v):
    """An integer: int or NumPy integer, or a float with no fraction (10.0); not a bool."""
    return _isnum(v) and float(v).is_integer()


def number(lo=None, hi=None, loOpen=False, hiOpen=False):
    """Validator of a finite real number in [lo, hi] (open ends with loOpen /
    hiOpen; None: unbounded); the value is kept as a float."""
    def check(v):
        if _isnum(v):
            f = float(v)
            if ((lo is None or (f > lo if loOpen else f >= lo)) and (hi is None or (f < hi if hiOpen else f <= hi))):
                return None
        return "must be a number" + _range(lo, hi, loOpen, hiOpen)
    check.convert = float
    return check


def integer(lo=None, hi=None, extra=""):
    """Validator of an integer in [lo, hi] (int, NumPy integer or a float with
    no fraction; not a bool); the value is kept as an int.  ``extra``: what
    the values mean, appended to the message."""
    def check(v):
        if _isint(v) and (lo is None or v >= lo) and (hi is None or v <= hi):
            return None
        return "must be an integer" + _range(lo, hi, False, False) + extra
    check.convert = int
    return check


def _range(lo, hi, loOpen, hiOpen):
    def f(x):
        return str(x) if isinstance(x, int) else "%g" % x
    if lo is not None and hi is not None:
        return " in %s%s, %s%s" % ("(" if loOpen else "[", f(lo), f(hi), ")" if hiOpen else "]")
    if lo is not None:
        return " %s %s" % (">" if loOpen else ">=", f(lo))
    if hi is not None:
        return " %s %s" % ("<" if hiOpen else "<=", f(hi))
    return ""


def boolean(v):
    """Validator of a flag: True or False (NumPy bools and the integers 0 and 1
    too, as YADE scripts write them); a string such as 'no' is refused, as
    it would count as True."""
    if isinstance(v, (bool, np.bool_)) or (isinstance(v, numbers.Integral) and v in (0, 1)):
        return None
    return "must be True or False"


boolean.convert = bool

positive = number(0, loOpen=True)
nonNegative = number(0)


class WorldSetting(Attr):
    """An engine attribute that is a setting of the engine's QDEM world: read
    from and written to ``obj.world.core`` while the engine is the one that
    steps that world, and kept in the engine's own ``_own`` as well, so that
    creating another engine (a dead one, a throw-away one to read a stable
    step) never changes the settings of the one that runs (engine.py,
    ``_activate``).  Built
    from the setting's one declaration in C++ (pkg/step/Settings.hpp, exposed
    as ``qdem._core.settings``): default, docstring and allowed values."""

    def __init__(self, decl):
        self.decl = decl
        default = decl["default"]
        if decl["kind"] == "choice":
            default = decl["choices"][default]
        super().__init__(default, decl["doc"])

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        if not obj._ownsSettings():  # (another engine steps this world: this one's own values)
            return obj._own[self.name]
        v = getattr(obj.world.core, self.decl["name"])
        if self.decl["kind"] == "choice":
            return self.decl["choices"][v]
        if self.decl["kind"] == "integer":
            return int(v)
        return bool(v) if self.decl["kind"] == "bool" else float(v)

    def __set__(self, obj, value):
        d = self.decl
        if d["kind"] == "choice":
            if value not in d["choices"]:
                raise ValueError("%s: %s=%r is invalid: must be one of %s"
                                 % (type(obj).__name__, self.name, value, d["choices"]))
            value = d["choices"].index(value)
        elif d["kind"] == "integer":
            ok = _isint(value)
            if ok:
                v = int(value)
                ok = (v > d["lo"] if d["loOpen"] else v >= d["lo"]) and (v < d["hi"] if d["hiOpen"] else v <= d["hi"])
            if not ok:
                raise ValueError("%s: %s=%r is invalid: must be a whole number, %s"
                                 % (type(obj).__name__, self.name, value, d["rule"]))
            value = int(value)
        elif d["kind"] == "real":
            ok = _isnum(value)
            if ok:
                v = float(value)
                ok = (v > d["lo"] if d["loOpen"] else v >= d["lo"]) and (v < d["hi"] if d["hiOpen"] else v <= d["hi"])
            if not ok:
                raise ValueError("%s: %s=%r is invalid: %s" % (type(obj).__name__, self.name, value, d["rule"]))
            value = float(value)
        else:
            msg = boolean(value)
            if msg:
                raise ValueError("%s: %s=%r is invalid: %s" % (type(obj).__name__, self.name, value, msg))
            value = bool(value)
        obj._own[self.name] = d["choices"][value] if d["kind"] == "choice" else value
        if obj._ownsSettings():
            setattr(obj.world.core, d["name"], value)


def worldSettings(namespace):
    """Adds a WorldSetting to a class body (``worldSettings(locals())``) for each
    world setting that has an engine name, in declaration order."""
    for decl in _core.settings:
        if decl["engineName"]:
            namespace[decl["engineName"]] = WorldSetting(decl)
