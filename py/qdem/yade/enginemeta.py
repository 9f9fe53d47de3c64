"""The metaclass of qdem's YADE engines (QdemEngine, VtkRecorder): help() and
dir() show the engine's own documented attributes and methods, not the ~140
lines YADE's PyRunner, PeriodicEngine, Engine and Serializable add."""
from yade import PyRunner

from ..attrs import AttrObject


class EngineMeta(type(PyRunner)):
    def __dir__(cls):
        own = set(AttrObject.attrNames.__func__(cls)) | set(getattr(cls, "_public", ())) | {"__init__"}
        return sorted(k for k in type.__dir__(cls) if k in own)
