"""The documentation site (doc/, `make doc`): it builds with warnings as
errors, its API reference holds every public name of qdem, and the settings
tables it generates follow their one declaration.

The build takes ~15-30 s on a 2-core machine (Sphinx reading ~20 pages and
importing qdem for autodoc)."""
import os
import subprocess
import sys

import pytest

# One build for the module's tests: they share a worker under pytest-xdist.
pytestmark = pytest.mark.xdist_group("docsite")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "doc", "_ext"))


def _env():
    import qdem
    import yade
    pkg = os.path.dirname(os.path.dirname(os.path.abspath(qdem.__file__)))
    yadePy = os.path.dirname(os.path.dirname(os.path.abspath(yade.__file__)))
    return dict(os.environ, PYTHONPATH=os.pathsep.join([pkg, yadePy]), OMP_NUM_THREADS="1")


def _python():
    """A plain interpreter (YADE's is a launcher script)."""
    exe = sys.executable
    return exe if os.path.basename(exe).startswith("python") else "/usr/bin/python3.11"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    r = subprocess.run([_python(), "-m", "sphinx", "-b", "html", "-q", "-W", "--keep-going", "-d",
                        str(out / "doctrees"), os.path.join(ROOT, "doc"), str(out / "html")],
                       env=_env(), capture_output=True, text=True, timeout=900)
    return r, out / "html"


def test_site_builds_with_warnings_as_errors(site):
    """A broken cross-reference, a public name without a docstring, a
    settings table from a stale build: each is a warning, and -W fails on it."""
    r, html = site
    assert r.returncode == 0, "make doc fails:\n" + r.stdout[-3000:] + r.stderr[-5000:]
    assert (html / "index.html").exists() and (html / "reference" / "settings.html").exists()


def test_every_public_name_is_in_the_reference(site):
    """Every name of qdem.__all__ and of its public submodules' __all__ is a
    documented object of the site (its inventory, objects.inv)."""
    from qdemdoc import publicNames
    from sphinx.util.inventory import InventoryFile
    r, html = site
    assert r.returncode == 0, r.stderr[-3000:]
    with open(html / "objects.inv", "rb") as f:
        inv = InventoryFile.load(f, "", os.path.join)
    documented = set()
    for kind, entries in inv.items():
        if kind.startswith("py:"):
            documented |= set(entries)
    names = publicNames()
    assert "qdem.addPiece" in names and "qdem.modes.viscosityForDamping" in names
    missing = [n for n in names if n not in documented]
    assert not missing, "public names missing from the API reference: %s" % missing


def test_performance_page_draws_its_roofline_from_kept_json(site):
    """The roofline plot is drawn at build time from the JSON under
    bench/logs/ (the bench-figure directive), never a PNG kept by hand: the
    page shows it and names the JSON it was drawn from."""
    r, html = site
    assert r.returncode == 0, r.stderr[-3000:]
    png = html / "_images" / "roofline.png"
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20000
    page = (html / "performance.html").read_text()
    assert "roofline.png" in page and "bench/logs/roofline_2026-11-24.json" in page


def test_settings_table_lists_every_engine_setting_with_its_default(site):
    """The QdemEngine table names each declared world setting and shows its
    compiled default: the table is generated, never written by hand."""
    from qdem import _core
    r, html = site
    text = (html / "reference" / "settings.html").read_text()
    for d in _core.settings:
        if d["engineName"]:
            assert ">%s<" % d["engineName"] in text, d["engineName"]
    assert "frictionRegVelocity" in text and "m/s" in text   # a unit read from the declaration


def test_a_stale_settings_table_is_detected():
    """The build compares the settings compiled into qdem._core with
    QDEM_SETTINGS in pkg/step/Settings.hpp: equal here; a setting declared
    but not compiled (a stale build) is a difference, which the build turns
    into a warning and -W into a failure."""
    from qdemdoc import settingsDrift
    declared, compiled = settingsDrift()
    assert declared == compiled and len(declared) > 10
    text = open(os.path.join(ROOT, "pkg", "step", "Settings.hpp")).read()
    stale = text.replace("#define QDEM_SETTINGS(X)", "#define QDEM_SETTINGS(X) X(bool, newSwitch, \"newSwitch\", "
                         "false, anyValue(), \"A setting added to the header, not yet compiled.\")", 1)
    declared, compiled = settingsDrift(stale)
    assert declared != compiled and "newSwitch" in declared


def test_render_is_loaded_on_first_use_without_vtk_at_import():
    """`import qdem` gives qdem.render without `import qdem.render`, and
    neither VTK nor the module is loaded until a script uses it."""
    code = ("import sys, qdem\n"
            "assert 'qdem.io.render' not in sys.modules and not any(m.startswith('vtkmodules') for m in sys.modules)\n"
            "f = qdem.render.snapshot\n"
            "assert 'qdem.io.render' in sys.modules and callable(f)\n"
            "assert 'render' in dir(qdem)\n"
            "try:\n    qdem.noSuchThing\nexcept AttributeError as e:\n    assert 'noSuchThing' in str(e)\n"
            "print('ok')\n")
    r = subprocess.run([_python(), "-c", code], env=_env(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "ok" in r.stdout, r.stdout + r.stderr


def test_every_public_name_of_qdem_is_in_its_all():
    """The reference lists qdem.__all__: a public name imported into qdem
    but left out of __all__ would be missing from it unnoticed."""
    import types
    import qdem
    left = [n for n, v in vars(qdem).items()
            if not n.startswith("_") and not isinstance(v, types.ModuleType) and n not in qdem.__all__]
    assert not left, "add to qdem.__all__ (py/qdem/__init__.py) so the API reference lists them: %s" % left
    for n in qdem.__all__:
        assert getattr(qdem, n).__doc__, "qdem.%s has no docstring" % n


def test_readme_starts_a_newcomer_with_the_two_commands():
    """README.md: at most 90 lines, opening with `make demo` and `make test`."""
    import re
    text = open(os.path.join(ROOT, "README.md")).read()
    assert len(text.splitlines()) <= 90
    first = re.search(r"```sh\n(.*?)```", text, re.S).group(1).splitlines()
    assert [x.split()[:2] for x in first] == [["make", "demo"], ["make", "test"]]
    assert text.index("```sh") < text.index("\n## ")
