"""The module paths qdem had before its layers (qdem.engine, qdem.shogi,
qdem.parallel, ...), kept as deprecated aliases: ``import qdem.engine`` (or
``qdem.engine``, ``from qdem import shogi``) warns once with a
DeprecationWarning naming the new path and gives the module at that path.
Scenes saved by O.save before the move name ``qdem.engine._step`` and
``qdem.recorder._record`` in their PyRunner commands: they load and run."""
import importlib
import importlib.abc
import importlib.util
import sys
import warnings

#: old submodule name -> the module(s) now holding its names (looked up in order)
MOVED = {
    "engine": ("qdem.yade.engine",),
    "lifecycle": ("qdem.yade.lifecycle",),
    "recorder": ("qdem.yade.recorder",),
    "setupcheck": ("qdem.yade.setupcheck",),
    "spheres": ("qdem.yade.spheres",),
    "yadeglue": ("qdem.yade.glue",),
    "yadeclass": ("qdem.yade.enginemeta",),
    "mpyglue": ("qdem.yade.mpy",),
    "parallel": ("qdem.mpi.ranks", "qdem.yade.mpy"),
    "cad": ("qdem.io.cad",),
    "plot": ("qdem.io.plot",),
    "render": ("qdem.io.render",),
    "restart": ("qdem.io.restart",),
    "vtu": ("qdem.io.vtu",),
    "shogi": ("qdem.scenes.shogi",),
}


def _forwarder(name, targets):
    """A module whose attributes are looked up in `targets`, imported on first use."""
    def __getattr__(attr):
        for t in targets:
            try:
                return getattr(importlib.import_module(t), attr)
            except AttributeError:
                continue
        raise AttributeError("module %r has no attribute %r (now in %s)" % (name, attr, " or ".join(targets)))
    return __getattr__


class MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``qdem.<old>`` for the names of MOVED (on sys.meta_path)."""

    def find_spec(self, fullname, path=None, target=None):
        head, _, tail = fullname.partition(".")
        if head != "qdem" or tail not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        return None  # (a plain module: replaced below by the one at the new path)

    def exec_module(self, module):
        old = module.__name__
        targets = MOVED[old.partition(".")[2]]
        warnings.warn("%s is deprecated: use %s" % (old, " and ".join(targets)), DeprecationWarning, stacklevel=2)
        if len(targets) == 1:
            sys.modules[old] = importlib.import_module(targets[0])  # (the import statement returns this one)
        else:
            module.__getattr__ = _forwarder(old, targets)
            module.__doc__ = "Deprecated: the names of %s." % " and ".join(targets)


def install():
    """Puts MovedFinder on sys.meta_path (once per process)."""
    if not any(isinstance(f, MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())  # (first: a stale qdem/engine.py of an old install never shadows it)


def moduleFor(name):
    """qdem.<name> for an old submodule name (qdem.__getattr__), with its warning."""
    return importlib.import_module("qdem." + name)
