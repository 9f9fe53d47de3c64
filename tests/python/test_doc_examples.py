"""Every ```python example in README.md and the documentation site's pages
(doc/**/*.md, not the developers' notebook doc/dev/) runs as written, in a
fresh `yade -n -x` process, and gives the right physics.

Each block is run verbatim with an epilogue that reports what it left behind
(pieces: inverted elements, centroid, speed, orientation; the floor force).
Long runs are shortened by capping O.run's step count (QDEM_EXAMPLE_STEPS
steps at most), so "short" means: the same script, fewer steps.  Checks per
example are keyed by the file and the example's position in it."""
import json
import os
import re
import subprocess
import sys
import textwrap

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

_PROLOGUE = """
import os as _os
from yade import wrapper as _wrapper
_cap = int(_os.environ.get("QDEM_EXAMPLE_STEPS", "0"))
if _cap > 0:
    _origRun = _wrapper.Omega.run
    def _cappedRun(self, nSteps=-1, wait=False):
        n = _cap if nSteps is None or nSteps < 0 else min(int(nSteps), _cap)
        return _origRun(self, n, wait)
    _wrapper.Omega.run = _cappedRun
"""

_EPILOGUE = """
import json as _json, numpy as _np, qdem as _qdem
from yade import O as _O
_out = {"iter": _O.iter, "pieces": []}
for _p in _qdem.defaultWorld().pieces:
    _x, _t = _p.pos, _p.tets
    _d = _np.einsum("ij,ij->i", _np.cross(_x[_t[:, 1]] - _x[_t[:, 0]], _x[_t[:, 2]] - _x[_t[:, 0]]),
                    _x[_t[:, 3]] - _x[_t[:, 0]])
    _X, _y = _p.refPos - _p.refPos.mean(0), _x - _x.mean(0)
    _U, _s, _Vt = _np.linalg.svd(_X.T @ _y)
    _R = (_U @ _np.diag([1, 1, _np.sign(_np.linalg.det(_U @ _Vt))]) @ _Vt).T
    _out["pieces"].append({"inverted": int((_d <= 0).sum()), "centroid": list(map(float, _p.centroid)),
                           "vmax": float(_np.abs(_p.vel).max()), "mass": float(_p.totalMass),
                           "upAxis": float(_np.abs(_R[2, :]).max())})
_walls = [b.id for b in _O.bodies if b is not None and type(b.shape).__name__ == "Wall"]
_out["wallForces"] = [list(map(float, _O.forces.f(i))) for i in _walls]
_out["spheres"] = [[float(b.state.pos[2]), float(b.shape.radius)] for b in _O.bodies
                   if b is not None and type(b.shape).__name__ == "Sphere"]
with open(_os.environ["QDEM_EXAMPLE_REPORT"], "w") as _f:
    _json.dump(_out, _f)
"""


def _examples():
    doc = os.path.join(ROOT, "doc")
    pages = []
    for d, dirs, fs in os.walk(doc):
        dirs[:] = [x for x in dirs if x not in ("dev", "_build", "_ext")]
        pages += [os.path.join(d, f) for f in fs if f.endswith(".md")]
    files = [os.path.join(ROOT, "README.md")] + sorted(pages)
    out = []
    for path in files:
        text = open(path).read()
        for k, m in enumerate(re.finditer(r"```python\n(.*?)```", text, re.S)):
            # (a block inside a list item is indented with it)
            out.append(pytest.param(path, k, textwrap.dedent(m.group(1)), id="%s#%d" % (os.path.relpath(path, ROOT), k)))
    return out


def _readmeDrop(r):
    """README: a soft cube dropped flat onto a floor lands flat, uninverted, where it fell."""
    (p,) = r["pieces"]
    assert p["inverted"] == 0
    assert abs(p["centroid"][0]) < 0.01 and abs(p["centroid"][1]) < 0.01
    assert p["upAxis"] > 0.9998   # a face up within ~1 degree
    assert p["vmax"] < 1e-3       # at rest
    (F,) = r["wallForces"]
    assert -F[2] == pytest.approx(p["mass"] * 9.81, rel=0.01) and abs(F[0]) + abs(F[1]) < 0.01 * p["mass"] * 9.81


def _spheresOnBlock(r):
    """doc/spheres.md: three spheres dropped onto a block rest on its top face (z = 0.105 m)."""
    (p,) = r["pieces"]
    top = p["centroid"][2] + 0.05
    assert len(r["spheres"]) == 3
    for z, radius in r["spheres"]:
        assert top + 0.5 * radius < z < top + radius + 0.005 + 0.002   # on the face, not through it


CHECKS = {("README.md", 0): (None, _readmeDrop), ("doc/spheres.md", 0): (None, _spheresOnBlock)}   # (step cap or None for the whole run, check)


@pytest.mark.parametrize("path,index,code", _examples())
def test_example_runs_as_written(tmp_path, path, index, code):
    rel = os.path.relpath(path, ROOT)
    cap, check = CHECKS.get((rel, index), (200, None))
    script = tmp_path / "example.py"
    script.write_text(_PROLOGUE + "\n" + code + "\n" + _EPILOGUE)
    report = tmp_path / "report.json"
    env = dict(os.environ, QDEM_EXAMPLE_REPORT=str(report), QDEM_EXAMPLE_STEPS=str(cap or 0),
               OMP_NUM_THREADS="1")
    r = subprocess.run(["timeout", "600", "yade", "-n", "-x", str(script)], cwd=str(tmp_path), env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, "%s example %d failed:\n%s\n%s" % (rel, index, r.stdout[-3000:], r.stderr[-3000:])
    res = json.load(open(report))
    for p in res["pieces"]:
        assert p["inverted"] == 0, "%s example %d leaves %d inverted elements" % (rel, index, p["inverted"])
    if check:
        check(res)
    sys.stdout.write("%s#%d: %s\n" % (rel, index, json.dumps(res)[:300]))


def test_default_demo_block_comes_to_rest_on_the_floor(tmp_path):
    """`make demo`'s scene (scripts/demo.py): the tilted soft block lands on an
    edge, settles on a face, and the floor carries its weight (1 %), with no
    element inverted; it writes its VTU series, energy plot and picture."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r = subprocess.run(["timeout", "600", "yade", "-n", "-x", os.path.join(ROOT, "scripts", "demo.py"), "4.0"],
                       cwd=str(tmp_path), env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    line = [x for x in r.stdout.splitlines() if "the floor carries" in x][0]
    ratio = float(re.search(r"ratio ([0-9.]+)", line).group(1))
    contacts = int(re.search(r"through (\d+) node-wall contacts", line).group(1))
    inverted = int(re.search(r"(\d+) elements inverted at most", line).group(1))
    assert ratio == pytest.approx(1.0, abs=0.01) and contacts >= 70 and inverted == 0
    out = tmp_path / "out" / "demo"
    assert (out / "block.png").stat().st_size > 10000 and (out / "energy.png").exists() and (out / "block.pvd").exists()
