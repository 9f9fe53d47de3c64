"""The qdem package in layers (doc/architecture.md, 'The Python package'):
each module imports only modules of its own layer or of the layers below, the
imports between qdem's modules form no circle, and no import hides inside a
function to dodge one.  Read from the source (py/qdem) with ast, so a new
module or import is checked without running it; QDEM_PACKAGE_DIR checks
another copy of the package.

Layers, bottom to top: the model (qdem's own modules: attrs, mesh, material,
piece, world, ...; no YADE), qdem.mpi, qdem.io, qdem.yade (needs YADE),
qdem.scenes, and the user API (qdem/__init__.py)."""
import ast
import os
import subprocess
import sys
import warnings

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PACKAGE = os.environ.get("QDEM_PACKAGE_DIR", os.path.join(ROOT, "py", "qdem"))

#: layer of each subpackage (a module outside them is the model, layer 0)
LAYERS = {"qdem.mpi": 1, "qdem.io": 2, "qdem.yade": 3, "qdem.scenes": 4}
API = 5  # qdem/__init__.py and its helper for the old module paths
LAYER_NAMES = {0: "the model", 1: "qdem.mpi", 2: "qdem.io", 3: "qdem.yade", 4: "qdem.scenes", 5: "the API"}

#: Modules a function may import: heavy or optional ones that `import qdem`
#: must not load (VTK and matplotlib: a second each; gmsh resets SIGINT;
#: mpi4py initialises MPI, which a serial run must not; meshio and scipy:
#: only for some files and for modes).  `yade` too, below qdem.yade only:
#: the model runs without YADE and asks for its scene when it is there.
LAZY_ALLOWED = {"matplotlib", "mpl_toolkits", "vtkmodules", "gmsh", "meshio", "scipy", "mpi4py"}


def _modules():
    """{dotted name: path} of every module of the package."""
    out = {}
    for d, _, files in os.walk(PACKAGE):
        for f in files:
            if not f.endswith(".py"):
                continue
            rel = os.path.relpath(os.path.join(d, f), PACKAGE)[:-3].split(os.sep)
            if rel[-1] == "__init__":
                rel = rel[:-1]
            out[".".join(["qdem"] + rel)] = os.path.join(d, f)
    return out


MODULES = _modules()
# The compiled extension has no source: a module of the model.
KNOWN = set(MODULES) | {"qdem._core"}


def layerOf(name):
    if name in ("qdem", "qdem._moved"):
        return API
    for pkg, layer in LAYERS.items():
        if name == pkg or name.startswith(pkg + "."):
            return layer
    return 0


def _imports(name, path):
    """(target, lineno, inFunction) of every import statement of a module;
    targets resolved to qdem modules where they are ones."""
    tree = ast.parse(open(path).read(), path)
    isPackage = os.path.basename(path) == "__init__.py"
    package = name if isPackage else name.rpartition(".")[0]
    out = []

    def visit(node, inFunction):
        for child in ast.iter_child_nodes(node):
            nested = inFunction or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import):
                for a in child.names:
                    out.append((a.name, child.lineno, inFunction))
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")
                    base = base[:len(base) - (child.level - 1)]
                    mod = ".".join(base + ([child.module] if child.module else []))
                else:
                    mod = child.module
                for a in child.names:
                    sub = mod + "." + a.name
                    out.append((sub if sub in KNOWN else mod, child.lineno, inFunction))
            visit(child, nested)
    visit(tree, False)
    return out


IMPORTS = {name: _imports(name, path) for name, path in MODULES.items()}


def _where(name, line):
    return "%s:%d" % (os.path.relpath(MODULES[name], ROOT), line)


def test_every_import_goes_down_the_layers():
    """A module imports qdem modules of its own layer or below only (the
    model never imports qdem.yade, qdem.io never imports qdem.yade, ...)."""
    bad = []
    for name, imports in IMPORTS.items():
        for target, line, _ in imports:
            if target in KNOWN and layerOf(target) > layerOf(name):
                bad.append("%s: %s (%s) imports %s (%s)" % (_where(name, line), name, LAYER_NAMES[layerOf(name)],
                                                            target, LAYER_NAMES[layerOf(target)]))
    assert not bad, "imports up the layers:\n" + "\n".join(bad)


def test_no_import_circle_between_qdem_modules():
    """The graph of imports between qdem's modules (at any depth of the
    code) is acyclic: a circle is named module by module."""
    graph = {name: sorted({t for t, _, _ in imports if t in MODULES and t != name})
             for name, imports in IMPORTS.items()}
    state, stack, circles = {}, [], []

    def walk(n):
        state[n] = 1
        stack.append(n)
        for m in graph[n]:
            if state.get(m) == 1:
                circles.append(" -> ".join(stack[stack.index(m):] + [m]))
            elif m not in state:
                walk(m)
        stack.pop()
        state[n] = 2
    for n in sorted(graph):
        if n not in state:
            walk(n)
    assert not circles, "import circles in qdem:\n" + "\n".join(circles)


def test_functions_import_only_heavy_optional_modules():
    """An import inside a function is for a heavy or optional module only
    (LAZY_ALLOWED; `yade` below qdem.yade), never for a qdem module (that
    hides a circle) nor for the standard library (it belongs at the top)."""
    bad = []
    for name, imports in IMPORTS.items():
        for target, line, inFunction in imports:
            if not inFunction:
                continue
            top = target.split(".")[0]
            if top in LAZY_ALLOWED or (top == "yade" and layerOf(name) < LAYERS["qdem.yade"]):
                continue
            bad.append("%s: %s imports %s inside a function" % (_where(name, line), name, target))
    assert not bad, "function-level imports:\n" + "\n".join(bad)


def test_layers_below_the_host_do_not_import_yade():
    """The model, qdem.mpi and qdem.io run without YADE: none imports it at
    module level."""
    bad = ["%s: %s imports %s" % (_where(name, line), name, target)
           for name, imports in IMPORTS.items() if layerOf(name) < LAYERS["qdem.yade"]
           for target, line, inFunction in imports if not inFunction and target.split(".")[0] == "yade"]
    assert not bad, "\n".join(bad)


def test_import_qdem_outside_yade_loads_no_host_vtk_or_mpi():
    """Plain Python (no YADE): `import qdem` works, and loads neither
    qdem.yade, VTK, matplotlib, gmsh nor mpi4py."""
    code = ("import sys, qdem\n"
            "assert 'yade' not in sys.modules, 'yade'\n"
            "heavy = [m for m in sys.modules if m.split('.')[0] in ('qdem', 'vtkmodules', 'matplotlib', 'gmsh',"
            " 'mpi4py') and (m.startswith('qdem.yade') or not m.startswith('qdem'))]\n"
            "assert not heavy, heavy\n"
            "print('ok')\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.path.dirname(os.path.dirname(os.path.abspath(__import__("qdem").__file__)))
    r = subprocess.run(["/usr/bin/python3.11", "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "ok" in r.stdout, r.stdout + r.stderr


def test_old_module_paths_warn_and_give_the_moved_module():
    """qdem.engine, qdem.shogi, qdem.parallel, ... (the paths before the
    layers) still work, with a DeprecationWarning naming the new path; the
    public names and qdem.render / qdem.plot give no warning."""
    pytest.importorskip("yade")
    import importlib

    import qdem
    import qdem.yade.engine
    for old in ("engine", "shogi", "parallel", "recorder"):
        sys.modules.pop("qdem." + old, None)
        qdem.__dict__.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        engine = importlib.import_module("qdem.engine")
        shogi = qdem.shogi
        parallel = importlib.import_module("qdem.parallel")
    said = [str(w.message) for w in caught if issubclass(w.category, DeprecationWarning)]
    assert any("qdem.engine is deprecated: use qdem.yade.engine" in s for s in said), said
    assert any("qdem.shogi is deprecated: use qdem.scenes.shogi" in s for s in said), said
    assert engine is qdem.yade.engine and engine.QdemEngine is qdem.QdemEngine
    assert engine._step is qdem.yade.engine._step  # (the command of scenes saved before the move)
    assert shogi.mesh is qdem.scenes.shogi.mesh
    assert parallel.isWriter is qdem.mpi.isWriter and parallel.assignSubdomains is qdem.yade.mpy.assignSubdomains
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert callable(qdem.render.snapshot) and callable(qdem.plot.energyPlot)
        for n in qdem.__all__:
            getattr(qdem, n)
