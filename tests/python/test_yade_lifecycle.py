"""QDEM in YADE's scene life cycle (issue 15): O.save/O.load in every format
and O.saveTmp/O.loadTmp continue to the bit, O.reset empties the QDEM world,
QDEM errors reach the script as themselves, set-up mistakes are refused at
the first step, help() and dict() show QDEM's settings."""
import io
import contextlib
import os
import subprocess
import textwrap

import numpy as np
import pytest

import qdem
from conftest import rubber

SCENE = """
import sys, numpy as np, qdem
from yade import O, ForceResetter, NewtonIntegrator, utils
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=20, radius=0.01)
block = qdem.addPiece(qdem.boxMesh((0.4, 0.4, 0.4), (3, 3, 3)), mat, pos=(0, 0, 0.3), angVel=(0, 1, 0))
other = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), mat, pos=(0.45, 0, 0.3), vel=(-1, 0, 0))
O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"),
             qdem.VtkRecorder(fileBase="frames/f-", iterPeriod=250), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.8 * qe.stableTimeStep()
O.trackEnergy = True
"""


def _yade(tmp_path, code, name="s.py"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(code))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run(["timeout", "300", "yade", "-n", "-x", str(path)], cwd=str(tmp_path), env=env,
                          capture_output=True, text=True)


@pytest.mark.parametrize("ext", ["yade", "yade.gz", "yade.bz2", "xml"])
def test_save_and_load_in_a_new_process_continue_to_the_bit(tmp_path, ext):
    r = _yade(tmp_path, SCENE + """
O.run(600, True)
O.save("scene.%s")
O.run(500, True)
np.save("ref.npy", np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel]))
""" % ext, "save.py")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    r = _yade(tmp_path, """
import numpy as np, qdem
from yade import O
O.load("scene.%s")
assert type(O.engines[1]).__name__ == "QdemEngine" and type(O.engines[2]).__name__ == "VtkRecorder"
assert qe is O.engines[1]                       # the label points at the engine
assert O.iter == 600 and qdem.defaultWorld().core.iter == 600
O.run(500, True)
ref = np.load("ref.npy")
now = np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel])
print("MAXDIFF", np.abs(now - ref).max(), "FRAMES", len(O.engines[2].frames))
""" % ext, "load.py")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    line = [x for x in r.stdout.splitlines() if x.startswith("MAXDIFF")][0].split()
    assert float(line[1]) == 0.0
    assert int(line[3]) == 5  # frames at 0, 250, 500 before the save; 750, 1000 after


def test_scene_to_string_and_back_in_a_new_process_continue_to_the_bit(tmp_path):
    """O.sceneToString / O.stringToScene: how yade.mpy sends the scene from
    rank 0 to its workers; the QDEM state travels with it."""
    r = _yade(tmp_path, SCENE + """
O.run(300, True)
open("scene.str", "wb").write(O.sceneToString())  # bytes
O.run(300, True)
np.save("ref.npy", np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel]))
""", "save.py")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    r = _yade(tmp_path, """
import numpy as np, qdem
from yade import O
O.stringToScene(open("scene.str", "rb").read())
assert type(O.engines[1]).__name__ == "QdemEngine" and O.iter == 300
O.run(300, True)
now = np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel])
print("MAXDIFF", np.abs(now - np.load("ref.npy")).max())
""", "load.py")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert float([x for x in r.stdout.splitlines() if x.startswith("MAXDIFF")][0].split()[1]) == 0.0


def test_reload_rewinds_qdem_and_reset_all_scenes_empties_it(tmp_path):
    """O.reload() (YADE loads O.filename in C++, past O.load) rewinds the
    QDEM state with the scene; O.resetAllScenes() empties the world."""
    r = _yade(tmp_path, SCENE + """
O.run(300, True)
O.save("r.yade.gz")
O.run(300, True)
ref = qdem.defaultWorld().core.pos.copy()
O.reload()
assert O.iter == 300 and qdem.defaultWorld().core.iter == 300, (O.iter, qdem.defaultWorld().core.iter)
O.run(300, True)
print("MAXDIFF", np.abs(qdem.defaultWorld().core.pos - ref).max())
O.resetAllScenes()
print("PIECES", len(qdem.defaultWorld().pieces))
""")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    out = dict(x.split()[:2] for x in r.stdout.splitlines() if x.startswith(("MAXDIFF", "PIECES")))
    assert float(out["MAXDIFF"]) == 0.0 and out["PIECES"] == "0"


def test_save_tmp_and_load_tmp_in_one_process(scene):
    O = scene
    from yade import ForceResetter, NewtonIntegrator, utils
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber(viscosity=10.0), pos=(0, 0, 0.2),
                  angVel=(1, 2, 0))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    O.run(300, True)
    O.saveTmp("a")
    O.run(400, True)
    ref = qdem.defaultWorld().core.pos.copy()
    O.loadTmp("a")
    # YADE and QDEM rewound together: the same iteration and time, one world
    core = qdem.defaultWorld().core
    assert O.iter == 300 and core.iter == 300 and core.time == pytest.approx(O.time, rel=1e-12)
    assert len(qdem.defaultWorld().pieces) == 1
    O.run(400, True)
    assert np.array_equal(qdem.defaultWorld().core.pos, ref)


def test_reset_empties_the_world_and_loading_a_plain_scene_too(scene, tmp_path):
    O = scene
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.reset()
    assert len(qdem.defaultWorld().pieces) == 0
    from yade import utils
    O.bodies.append(utils.sphere((0, 0, 0), 1))
    path = str(tmp_path / "plain.yade")
    O.save(path)
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.load(path)  # a scene with no QDEM: the old pieces must not leak into it
    assert len(qdem.defaultWorld().pieces) == 0


def test_engines_kept_across_reset_act_on_the_new_scene_with_their_settings(scene, tmp_path):
    """A sweep reusing one list of engines: after O.reset() they step the new
    pieces (they once stepped the emptied world: the new piece hung in the air)."""
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    engine = qdem.QdemEngine(damping=0.25, progressPeriod=0)
    recorder = qdem.VtkRecorder(fileBase=str(tmp_path / "f-"), iterPeriod=50)
    engines = [ForceResetter(), engine, recorder, NewtonIntegrator(gravity=(0, 0, -9.81))]
    for height in (1.0, 2.0):
        O.reset()
        p = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, height))
        O.engines = engines
        O.dt = 1e-4
        O.run(100, True)
        assert engine.world is qdem.defaultWorld() and recorder.world is qdem.defaultWorld()
        assert engine.damping == 0.25 and qdem.defaultWorld().core.localDamping == 0.25
        z = p.centroid[2]  # the piece fell (local damping slows it: compared below)
        assert z < height - 1e-4
        assert [f[1] for f in recorder.frames] == ["f-%06d.vtu" % i for i in (0, 50, 100)]
    O.reset()
    p = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 2.0))
    O.engines = [ForceResetter(), qdem.QdemEngine(damping=0.25), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 1e-4
    O.run(100, True)
    assert p.centroid[2] == z


def test_scene_with_qdem_engines_but_no_state_is_refused(scene, tmp_path):
    O = scene
    from yade import ForceResetter, NewtonIntegrator, wrapper
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator()]
    path = str(tmp_path / "nostate.yade")
    wrapper.Omega.save._qdemOrig(O, path)  # YADE's own save, as a script without qdem's wrappers would
    with pytest.raises(RuntimeError, match="no QDEM state"):
        O.load(path)


def test_qdem_errors_reach_the_script_as_themselves(scene):
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator()]
    O.dt = 3 * O.engines[1].stableTimeStep()
    with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
        O.step()
    with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
        O.run(5, True)
    O.run(5)
    with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
        O.wait()


def test_a_caught_error_loses_no_qdem_step(scene):
    """The retry pattern of doc/yade.md: a step refused for its O.dt, caught,
    O.dt lowered, the run goes on.  Before, YADE counted the refused step as
    done for the QdemEngine (a PyRunner), so the retry's first step skipped
    QDEM while NewtonIntegrator moved the sphere: QDEM's clock stayed a step
    behind YADE's and the piece fell behind a sphere let go beside it."""
    O = scene
    from yade import (Bo1_Sphere_Aabb, ForceResetter, InsertionSortCollider, InteractionLoop, NewtonIntegrator,
                      utils)
    piece = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber(), pos=(0, 0, 2))
    ball = O.bodies.append(utils.sphere((1, 0, 2), 0.05))
    qe = qdem.QdemEngine()
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]), InteractionLoop([], [], []), qe,
                 NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    core = qdem.defaultWorld().core
    good = 0.5 * qe.stableTimeStep()
    O.dt = good
    O.run(20, True)
    for retry in (lambda: O.run(20, True), O.step):
        O.dt = 3 * good
        with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
            retry()
        with pytest.raises(qdem.StabilityError, match="exceeds the stable time step"):
            O.step()  # (refused again: the step is QDEM's to refuse, not skipped)
        O.dt = good
        O.run(20, True)
        assert core.iter == O.iter
        assert core.time == pytest.approx(O.time, rel=1e-12)
        assert piece.velocity[2] == pytest.approx(O.bodies[ball].state.vel[2], rel=1e-9)


def _droppedBlock(O):
    from yade import ForceResetter, NewtonIntegrator, utils
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber(), pos=(0, 0, 0.3), angVel=(0, 2, 0))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    engine = qdem.QdemEngine()
    O.engines = [ForceResetter(), engine, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * engine.stableTimeStep()
    return block, engine


def test_the_old_engine_object_leaves_a_loaded_scene_s_settings_alone(scene):
    """After O.loadTmp the script still holds its engine object; touching it
    (here stableTimeStep()) copied its settings into the loaded scene, whose
    run then parted from the saved one.  The loaded scene keeps its own."""
    O = scene
    block, engine = _droppedBlock(O)
    O.run(10, True)
    O.saveTmp("rewind")
    O.run(150, True)
    ref = np.array(block.pos)
    engine.damping, engine.friction = 0.4, False
    O.run(10, True)
    O.loadTmp("rewind")
    engine.stableTimeStep()
    loaded = [e for e in O.engines if isinstance(e, qdem.QdemEngine)][0]
    assert loaded.damping == 0.0 and loaded.friction
    O.run(150, True)
    assert np.array_equal(np.array(qdem.defaultWorld().pieces[0].pos), ref)


def test_piece_handles_follow_a_rewind_and_refuse_another_scene(scene, tmp_path):
    """A Piece handle after O.loadTmp of the same scene (a rewind) reads and
    writes the loaded scene, as YADE body ids do; after O.load of a scene with
    other pieces it refuses, instead of reading the scene before the load and
    losing what is written to it."""
    O = scene
    block, _ = _droppedBlock(O)
    O.run(10, True)
    O.saveTmp("rewind")
    z0 = block.centroid[2]
    O.run(200, True)
    assert block.centroid[2] < z0 - 1e-3
    O.loadTmp("rewind")
    assert qdem.defaultWorld().pieces[0] is block
    assert block.centroid[2] == z0
    block.extForce[:, 2] = 1000.0 / len(block.mass)  # lifts it: the write reaches the loaded scene
    O.run(100, True)
    assert block.centroid[2] > z0
    # a scene with other pieces
    other = str(tmp_path / "other.yade")
    O.reset()
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 0.5))
    from yade import ForceResetter, NewtonIntegrator
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator()]
    O.save(other)
    O.reset()
    block2, _ = _droppedBlock(O)
    O.load(other)
    with pytest.raises(RuntimeError, match="qdem.defaultWorld\\(\\).pieces"):
        block2.centroid
    with pytest.raises(RuntimeError, match="before O.load"):
        block2.vel[:] = 0
    # O.loadTmp of a scene with other pieces: the refusal names the method called
    O.saveTmp("one")
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 1.0))
    extra = qdem.defaultWorld().pieces[-1]
    O.loadTmp("one")
    with pytest.raises(RuntimeError, match="before O.loadTmp,"):
        extra.centroid


def test_uncaught_error_ends_yade_with_a_nonzero_exit(tmp_path):
    r = _yade(tmp_path, SCENE + "O.dt = 3 * qe.stableTimeStep()\nO.run(10, True)\nprint('NOT REACHED')\n")
    assert r.returncode != 0
    assert "NOT REACHED" not in r.stdout
    assert "StabilityError" in r.stdout + r.stderr


@pytest.mark.parametrize("ext", ["yade.gz", "yade", "xml.bz2"])
def test_save_into_a_missing_directory_is_an_error_naming_it(tmp_path, ext):
    """YADE's gzip writer looped for good on a stream that failed to open:
    O.save('missing/x.yade.gz') hung with nothing printed (and plain YADE
    'saved' a small scene there, writing nothing)."""
    r = _yade(tmp_path, SCENE + textwrap.dedent("""
        O.run(5, True)
        try:
            O.save("missing_dir/scene.%s")
        except OSError as e:
            print("CAUGHT", e)
        print("DONE")
        """ % ext))
    out = r.stdout + r.stderr
    assert "DONE" in out, out[-3000:]
    assert "CAUGHT O.save: cannot write 'missing_dir/scene.%s'" % ext in out and "does not exist" in out, out[-3000:]
    assert not (tmp_path / "missing_dir").exists()


def _engines(order):
    from yade import ForceResetter, NewtonIntegrator
    made = {"F": ForceResetter, "Q": qdem.QdemEngine, "N": lambda: NewtonIntegrator(gravity=(0, 0, -9.81))}
    return [made[c]() for c in order]


@pytest.mark.parametrize("order,match", [("FNQ", "after NewtonIntegrator"), ("QFN", "ForceResetter is at"),
                                         ("FQ", "no NewtonIntegrator"), ("FQQN", "Two QdemEngines")])
def test_engine_order_mistakes_are_refused(scene, order, match):
    O = scene
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = _engines(order)
    O.dt = 1e-5
    with pytest.raises(qdem.SetupError, match=match):
        O.run(2, True)
    assert qdem.defaultWorld().core.iter == 0  # refused before any QDEM step


def test_gravity_engine_periodic_cell_and_skipped_steps_are_refused(scene):
    """Each ran silently: under a GravityEngine the piece floated while spheres fell; in
    a periodic cell it left the cell and spheres crossing the boundary passed through
    it; with iterPeriod=10 (set even mid-run) QDEM time ran at a tenth of O.time."""
    O = scene
    from yade import ForceResetter, GravityEngine, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), GravityEngine(gravity=(0, 0, -9.81)), qdem.QdemEngine(), NewtonIntegrator()]
    O.dt = 1e-5
    with pytest.raises(qdem.SetupError, match="GravityEngine at O.engines.1.*NewtonIntegrator.gravity"):
        O.run(2, True)
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.periodic = True
    O.cell.setBox(1, 1, 1)
    with pytest.raises(qdem.SetupError, match="periodic"):
        O.run(2, True)
    O.periodic = False
    O.run(3, True)
    O.engines[1].iterPeriod = 10
    with pytest.raises(qdem.SetupError, match="iterPeriod=10"):
        O.run(20, True)
    assert qdem.defaultWorld().core.iter == 3


@pytest.mark.parametrize("gravity", [(0, 0, float("nan")), (0, float("inf"), -9.81)])
def test_non_finite_gravity_is_refused_at_the_first_step(scene, gravity):
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=gravity)]
    O.dt = 1e-5
    with pytest.raises(ValueError, match="gravity .* is not finite"):
        O.run(5, True)
    assert qdem.defaultWorld().core.iter == 0  # at the first step, before any QDEM step


def test_newton_damping_with_spheres_and_pieces_warns(scene):
    O = scene
    from yade import (ForceResetter, InsertionSortCollider, InteractionLoop, NewtonIntegrator, utils,
                      Bo1_Sphere_Aabb, Ig2_Sphere_Sphere_ScGeom, Ip2_FrictMat_FrictMat_FrictPhys,
                      Law2_ScGeom_FrictPhys_CundallStrack)
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.bodies.append(utils.sphere((0, 0, 0.3), 0.02))
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                 [Law2_ScGeom_FrictPhys_CundallStrack()]),
                 qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.2)]
    O.dt = 1e-5
    with pytest.warns(RuntimeWarning, match="damps YADE bodies but not QDEM nodes"):
        O.run(2, True)


def test_material_edit_after_add_piece_is_refused():
    mat = rubber()
    mat.young = 2e7  # before use: fine
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (1, 1, 1)), mat)
    with pytest.raises(ValueError, match="cannot change young after addPiece"):
        mat.young = 3e7
    assert mat.young == 2e7
    piece = w.pieces[0]
    with pytest.raises(AttributeError, match="Piece.material is fixed"):
        piece.material = rubber(young=1e5)   # was silently ignored
    assert piece.material is mat


def test_help_dict_and_stable_time_step_like_yade(scene):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        help(qdem.QdemEngine)
    text = buf.getvalue()
    assert "checkPeriod (= 100)" in text and "sleepTime (= 0.01)" in text
    assert "iterPeriod" not in text and "virtPeriod" not in text  # PyRunner's own attributes are not listed
    e = qdem.QdemEngine(damping=0.1)
    d = e.dict()
    assert d["damping"] == 0.1 and "command" not in d and set(d) >= {"checkDt", "sleepVelocity", "friction"}
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    assert isinstance(e.stableTimeStep(), float)
    assert e.stableTimeStep() == e.stableDt()["combined"]


def test_progress_line_shows_share_done_and_time_left(scene):
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine(progressPeriod=100), NewtonIntegrator()]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        O.run(400, True)
    lines = [x for x in buf.getvalue().splitlines() if x.startswith("qdem:")]
    assert len(lines) == 4
    assert "100%" in lines[-1] and " 50%" in lines[1]
    assert all("ETA" in x for x in lines)  # the first line too: the rate since O.run started


def test_yade_batch_job_logs_are_ignored_by_git():
    """yade-batch writes each job's log beside its script ('$.@.log': script
    path, then the job's description); for every table in scripts/ those logs
    are ignored by git, so a batch run leaves the work tree clean."""
    import glob
    import re
    import shutil
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    if shutil.which("git") is None or not os.path.exists(os.path.join(root, ".git")):
        pytest.skip("not a git work tree")
    logs = []
    for table in glob.glob(os.path.join(root, "scripts", "**", "*.table"), recursive=True):
        text = open(table).read()
        script = re.search(r"yade-batch .*?\.table\s+(\S+\.py)", text)
        assert script, "%s: no 'yade-batch ... TABLE SCRIPT.py' command in its header" % table
        rows = [l.split() for l in text.splitlines() if l.strip() and not l.startswith("#")]
        head = rows[0]
        for row in rows[1:]:
            desc = ",".join("%s=%s" % (k, v.strip("'\"")) for k, v in zip(head, row))
            logs.append("%s.%s.log" % (script.group(1), desc))
    assert len(logs) >= 10
    r = subprocess.run(["git", "check-ignore", "--no-index", "-v"] + logs, cwd=root, capture_output=True, text=True)
    ignored = {l.split("\t")[-1] for l in r.stdout.splitlines()}
    assert ignored == set(logs), "not ignored: %s" % sorted(set(logs) - ignored)


def test_a_command_finds_its_engine_in_O_engines_and_nowhere_else(tmp_path):
    """The PyRunner command of a QdemEngine or VtkRecorder names an id, and the
    object is looked up in O.engines (YADE hands back the Python object): no
    table of engines keeps one alive or findable once it left O.engines."""
    from yade import O, ForceResetter, NewtonIntegrator
    from qdem.yade import lifecycle
    O.reset()
    e = qdem.QdemEngine(label="qeFind")
    r = qdem.VtkRecorder(fileBase=str(tmp_path / "find-"), iterPeriod=10)
    O.engines = [ForceResetter(), e, r, NewtonIntegrator()]
    assert lifecycle.engineFor(e.qdemId) is e
    assert lifecycle.engineFor(r.qdemId) is r
    O.engines = [ForceResetter(), NewtonIntegrator()]
    for obj in (e, r):  # still alive here, but no longer an engine of the scene
        with pytest.raises(RuntimeError, match="no engine for command id"):
            lifecycle.engineFor(obj.qdemId)
    O.reset()


def test_another_engine_does_not_change_the_running_one_s_settings(scene):
    """Settings live in the world; every new QdemEngine wrote its defaults
    there: a dead second engine (what the two-engines refusal suggests) or a
    throw-away QdemEngine() made to read a stable step silently put the
    running engine back to damping 0, friction on, explicit viscosity.  Each
    engine keeps its own now, and the one that steps has them in force."""
    O = scene
    from yade import ForceResetter, NewtonIntegrator, utils
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2)), rubber(viscosity=5.0), pos=(0, 0, 0.3))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    a = qdem.QdemEngine(damping=0.3, friction=False, viscousIntegration="implicit")
    b = qdem.QdemEngine(dead=True)
    O.engines = [ForceResetter(), a, b, NewtonIntegrator(gravity=(0, 0, -9.81))]
    core = qdem.defaultWorld().core
    wanted = (0.3, False, "implicit")
    assert (a.damping, a.friction, a.viscousIntegration) == wanted
    assert (b.damping, b.friction, b.viscousIntegration) == (0.0, True, "explicit")
    O.dt = 0.5 * a.stableTimeStep()
    O.run(5, True)
    assert (core.localDamping, core.frictionOn) == (0.3, False)
    throwAway = qdem.QdemEngine().stableTimeStep()  # computed with its own (default) settings
    assert throwAway > 0 and (a.damping, a.friction, a.viscousIntegration) == wanted
    O.run(5, True)
    assert (core.localDamping, core.frictionOn) == (0.3, False)
    a.damping = 0.1  # a change to the running engine goes into the world
    assert core.localDamping == 0.1


def test_save_during_a_background_run_is_refused_and_works_after_wait(scene, tmp_path):
    """O.save from the script while O.run() goes on in the background wrote
    QDEM's part and YADE's part from different steps (22 steps apart in a
    tester's run).  It is refused, naming the fix; after O.pause(); O.wait()
    the file is consistent."""
    O = scene
    block, _ = _droppedBlock(O)
    path = str(tmp_path / "bg.yade")
    O.run(1000000)
    try:
        with pytest.raises(RuntimeError, match=r"O.pause\(\) and O.wait\(\)"):
            O.save(path)
    finally:
        O.pause()
        O.wait()
    O.save(path)
    # Loaded in a fresh process: YADE's own O.load in the process that ran in
    # the background crashed now and then inside YADE (in the full suite).
    r = _yade(tmp_path, """
        import qdem
        from yade import O
        O.load(%r)
        print("ITERS", O.iter, qdem.defaultWorld().core.iter)
        """ % path, name="check.py")
    line = [x for x in r.stdout.splitlines() if x.startswith("ITERS")]
    assert line, r.stdout + r.stderr
    _, yadeIter, qdemIter = line[0].split()
    assert int(yadeIter) == int(qdemIter) == O.iter


def test_o_step_leaves_the_scripts_variables_alone(tmp_path):
    """YADE's PyRunner copies the innermost Python frame's locals into the
    script's globals; with qdem's wrapper of O.step that frame was the
    wrapper's, and every O.step() set the script's a, k, self and orig to the
    wrapper's arguments (a tester's step loop lost its piece, named a)."""
    r = _yade(tmp_path, SCENE + """
from yade import PyRunner
a, k, self, orig = block, 1e5, "mine", 7
O.engines = O.engines + [PyRunner(iterPeriod=1, command="pass")]
for i in range(3):
    O.step()
print("KEPT", a is block, k == 1e5, self == "mine", orig == 7)
""")
    assert "KEPT True True True True" in r.stdout, r.stdout + r.stderr
