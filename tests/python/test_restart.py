"""Restarts (qdem.saveState / loadState, py/qdem/restart.py): a run saved and
loaded into the same scene built again goes on exactly as if it had not
stopped - same positions and velocities to the bit, contact springs,
sleeping pieces and energies included; a different scene or a broken file is
refused with a message and leaves the world as it was."""
import os

import numpy as np
import pytest

import qdem
from conftest import rubber


def _floor(young=0.0):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense, o.young = 0, 0, 2, 1, young
    return o


def _scene(threads=1, floor=True):
    qdem._core.setThreads(threads)
    w = qdem.World()
    mat = rubber(radius=2e-3, viscosity=2000.0, frictionWall=0.0, frictionPiece=0.3)
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(-0.3, 0, 0.052), vel=(1.0, 0, 0))
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0.0, 0.02, 0.052))
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0.0, 0.02, 0.156))  # stacked on the second
    if floor:
        w.core.setObstacles([_floor()])
        w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    w.core.gravity = (0, 0, -9.81)
    w.core.trackEnergy = True
    w.core.sleepVelocity = 1e-3
    w.core.sleepTime = 0.01
    return w


def test_a_restarted_run_goes_on_exactly(tmp_path):
    path = str(tmp_path / "run.qdem.npz")
    w = _scene()
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 11000)         # the sliding block is about to hit the sleeping stack
    assert w.core.nAsleep >= 1
    qdem.saveState(path, world=w, scriptTime=1.25, label="run")
    w.core.step(dt, 5000)          # through the hit
    assert w.core.wakeCount >= 1 and w.core.contactCounts["pointPolygon"] > 0
    w2 = _scene()
    extra = qdem.loadState(path, world=w2)
    assert extra == {"scriptTime": 1.25, "label": "run"}
    w2.core.step(dt, 5000)
    assert np.array_equal(w2.core.pos, w.core.pos)
    assert np.array_equal(w2.core.vel, w.core.vel)
    assert w2.core.time == w.core.time and w2.core.iter == w.core.iter
    assert w2.core.energy == w.core.energy
    assert [w2.core.asleep(i) for i in range(3)] == [w.core.asleep(i) for i in range(3)]


def test_a_different_scene_or_a_broken_file_is_refused_and_changes_nothing(tmp_path):
    path = str(tmp_path / "run.qdem.npz")
    w = _scene()
    w.core.step(1e-5, 10)
    qdem.saveState(path, world=w)
    other = qdem.World()
    mat = rubber()
    other.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), mat)
    before = other.core.pos.copy()
    with pytest.raises(ValueError, match="build the same scene"):
        qdem.loadState(path, world=other)
    assert np.array_equal(other.core.pos, before)
    broken = tmp_path / "broken.npz"
    broken.write_bytes(open(path, "rb").read()[:100])
    with pytest.raises(ValueError, match="not a QDEM state file"):
        qdem.loadState(str(broken), world=_scene())
    assert not (tmp_path / "run.qdem.npz.tmp.npz").exists()


def test_sleeping_pieces_stay_asleep_when_a_restart_gives_the_same_obstacles(tmp_path):
    # A script restarting in a new process loads the state before its engine
    # has handed over the YADE bodies: the first setObstacles with the saved
    # list must not wake anybody, another list wakes every piece.
    path = str(tmp_path / "run.qdem.npz")
    w = _scene()
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 11000)
    asleep = [w.core.asleep(i) for i in range(3)]
    assert sum(asleep) >= 1
    qdem.saveState(path, world=w)
    for floor, young, wakes in ((False, 0.0, False), (True, 0.0, False), (False, 5e6, True)):
        w2 = _scene(floor=floor)
        qdem.loadState(path, world=w2)
        w2.core.setObstacles([_floor(young)])
        assert [w2.core.asleep(i) for i in range(3)] == ([False] * 3 if wakes else asleep), (floor, young)
    # A state file without the obstacle list (written before it was saved) wakes them.
    data = dict(np.load(path))
    del data["qdem:obstacles"]
    old = str(tmp_path / "old.npz")
    np.savez(old, **data)
    w3 = _scene(floor=False)
    qdem.loadState(old, world=w3)
    w3.core.setObstacles([_floor()])
    assert w3.core.nAsleep == 0


def _yadeScene(O):
    from yade import ForceResetter, NewtonIntegrator, utils
    O.reset()
    qdem.reset()
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), rubber(radius=2e-3, viscosity=2000.0),
                  pos=(0, 0, 0.052))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    engine = qdem.QdemEngine(sleepVelocity=1e-3, sleepTime=0.01, progressPeriod=500)
    O.engines = [ForceResetter(), engine, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.8 * engine.stableDt()["combined"]
    return qdem.defaultWorld().core


def test_a_yade_script_restarted_goes_on_asleep_and_on_the_qdem_clock(scene, tmp_path, capsys):
    path = str(tmp_path / "run.qdem.npz")
    core = _yadeScene(scene)
    for _ in range(40):
        scene.run(1000, True)
        if core.nAsleep:
            break
    assert core.nAsleep == 1
    qdem.saveState(path)
    iter0, time0 = core.iter, core.time
    core = _yadeScene(scene)     # a new run of the script: O.iter and O.time start from 0
    qdem.loadState(path)
    capsys.readouterr()
    scene.run(500, True)
    assert core.nAsleep == 1 and core.wakeCount == 0
    assert core.iter == iter0 + 500 and core.time == pytest.approx(time0 + 500 * scene.dt)
    line = [s for s in capsys.readouterr().out.splitlines() if s.startswith("qdem: step")][-1]
    assert line.startswith("qdem: step %d " % core.iter) and "nan" not in line


def test_save_state_into_a_missing_directory_names_the_path(tmp_path):
    """The error named the temporary file ('s.npz.tmp.npz'), not the path
    given, and did not say what was wrong."""
    w = _scene()
    path = str(tmp_path / "missing_dir" / "s.npz")
    with pytest.raises(FileNotFoundError) as e:
        qdem.saveState(path, world=w)
    msg = str(e.value)
    assert path in msg and ".tmp.npz" not in msg and "does not exist" in msg and "makedirs" in msg
    assert not os.path.exists(tmp_path / "missing_dir")
