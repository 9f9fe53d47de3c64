"""VTK output a ParaView user can trust (issue 15): frames written by VTK's
own writer, compressed, read back with VTK: tensor components in ParaView's
order, displacement and a deformation-only field, frame names and .pvd times
on YADE's clock, a frame of the initial state."""
import math
import os
import re

import numpy as np
import pytest

import qdem
from conftest import rubber
from qdem.io.vtu import readVtu


def test_recorder_series_reads_back_in_vtk(scene, tmp_path):
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    piece = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.1), (4, 2, 2)), rubber(viscosity=5.0),
                          vel=(2.0, 0, 0), angVel=(0, 0, 3.0))
    base = str(tmp_path / "out" / "f-")
    O.engines = [ForceResetter(), qdem.QdemEngine(), qdem.VtkRecorder(fileBase=base, iterPeriod=100),
                 NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(250, True)
    files = sorted(os.listdir(tmp_path / "out"))
    assert files == ["f-000000.vtu", "f-000100.vtu", "f-000200.vtu", "f.pvd"]
    pvd = open(tmp_path / "out" / "f.pvd").read()
    times = [float(t) for t in re.findall(r'timestep="([^"]+)"', pvd)]
    assert times[0] == 0.0
    np.testing.assert_allclose(times[1:], [100 * O.dt, 200 * O.dt], rtol=1e-12)
    # the last frame against the state it shows: rerun to step 200 is not needed,
    # the first frame is the reference shape, the last is read back and checked
    pts0, a0, _ = readVtu(base + "000000.vtu")
    np.testing.assert_array_equal(pts0, piece.refPos)
    assert np.abs(a0["displacement"]).max() == 0 and np.abs(a0["deformation"]).max() < 1e-15
    O.run(50, True)  # now at step 300: a frame, and the live state to compare with
    pts, a, comps = readVtu(base + "000300.vtu")
    np.testing.assert_allclose(pts, piece.pos, rtol=0, atol=1e-15)
    assert comps["stress"] == ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]
    s = piece.stress()  # (xx yy zz yz xz xy)
    np.testing.assert_allclose(a["stress"][:, 0], s[:, 0], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(a["stress"][:, 3], s[:, 5], rtol=1e-12, atol=1e-9)   # XY
    np.testing.assert_allclose(a["stress"][:, 4], s[:, 3], rtol=1e-12, atol=1e-9)   # YZ
    np.testing.assert_allclose(a["stress"][:, 5], s[:, 4], rtol=1e-12, atol=1e-9)   # XZ
    np.testing.assert_allclose(a["velocity"], piece.vel, rtol=1e-12)
    # flying and spinning: displacement holds the rigid motion, deformation does not
    flight = np.abs(a["displacement"]).max()
    assert flight > 0.01
    assert np.abs(a["deformation"]).max() < 1e-3 * flight
    np.testing.assert_allclose(a["volumeRatio"], 1.0, atol=1e-3)
    head = open(base + "000300.vtu", "rb").read(600).decode("latin-1")
    assert "vtkZLibDataCompressor" in head


def test_frames_follow_yades_clock_when_qdem_joins_a_running_scene(scene, tmp_path):
    """A QdemEngine added to a scene that has already run: QDEM's clock starts
    at YADE's, so frames are named by O.iter and timed by O.time (the first
    one the initial state of the pieces, at the step they joined)."""
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 1e-4
    O.run(130, True)
    t0 = O.time
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 1))
    base = str(tmp_path / "j-")
    O.engines = [ForceResetter(), qdem.QdemEngine(), qdem.VtkRecorder(fileBase=base, iterPeriod=100),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(200, True)
    assert qdem.defaultWorld().core.iter == O.iter and qdem.defaultWorld().core.time == O.time
    assert sorted(os.listdir(tmp_path)) == ["j-000130.vtu", "j-000200.vtu", "j-000300.vtu", "j.pvd"]
    times = [float(t) for t in re.findall(r'timestep="([^"]+)"', open(tmp_path / "j.pvd").read())]
    np.testing.assert_allclose(times, [t0, t0 + 70 * O.dt, t0 + 170 * O.dt], rtol=1e-12)


def test_vtu_refuses_nan_and_leaves_no_partial_file(tmp_path):
    from qdem.io.vtu import writeVtu
    path = str(tmp_path / "nan.vtu")
    with pytest.raises(ValueError, match="NaN"):
        writeVtu(path, np.eye(4, 3), [[0, 1, 2, 3]], pointData={"v": np.full(4, np.nan)})
    assert os.listdir(tmp_path) == []


def test_snapshot_draws_with_vtk_off_screen(tmp_path):
    """qdem.render draws with VTK (a private Xvfb when there is no display):
    no fallback warning, a PNG of the asked size, the pieces coloured by stress
    (red pixels where the compressed block is most stressed), a grey floor."""
    import warnings
    import matplotlib.image as mpimg
    from qdem import render
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), rubber(), pos=(0, 0, 0.105))
    p.pos[:, 2] = 0.005 + 0.8 * (p.pos[:, 2] - 0.005)  # squeezed: stress to colour
    path = str(tmp_path / "snap.png")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        vmax = render.snapshot(w, path, title="squeezed block", floor=0.0, size=(640, 400))
    img = mpimg.imread(path)
    assert img.shape[:2] == (400, 640)
    assert vmax == pytest.approx(np.max(p.vonMises()), rel=1e-12)
    rgb = img[..., :3]
    red = (rgb[..., 0] > 0.6) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)
    grey = (np.abs(rgb[..., 0] - rgb[..., 1]) < 0.04) & (np.abs(rgb[..., 1] - rgb[..., 2]) < 0.06) & \
        (rgb[..., 0] > 0.5) & (rgb[..., 0] < 0.8)
    assert red.mean() > 0.005 and grey.mean() > 0.05


def _line(n=8):
    """n upright blocks in a line along a diagonal of the floor, the 5th and
    6th falling (spun about the line's normal) and squeezed (stressed)."""
    w = qdem.World()
    axis = np.array([np.cos(0.5), np.sin(0.5), 0.0])
    pieces = [w.addPiece(qdem.boxMesh((0.02, 0.06, 0.1), (2, 3, 4)), rubber(), pos=tuple(0.06 * i * axis + [0, 0, 0.051]))
              for i in range(n)]
    for k in (4, 5):
        p = pieces[k]
        p.pos[:, 2] = 0.001 + 0.8 * (p.pos[:, 2] - 0.001)
        p.vel[:] = np.cross([-axis[1], axis[0], 0.0], p.pos - p.pos.mean(axis=0)) * 20.0 + 0.5 * axis
    pieces[0].vel[:] = 0.05 * axis  # a slow creep far behind: not the front
    return w, pieces


def _project(points, focal, position, up, angle, size):
    """Picture coordinates in [-1, 1] of points seen by a pinhole camera."""
    f = (np.asarray(focal) - position) / np.linalg.norm(np.asarray(focal) - position)
    r = np.cross(f, up)
    v = np.asarray(points) - position
    depth = v @ f
    t = np.tan(np.radians(angle) / 2)
    return np.c_[(v @ r) / (depth * t * size[0] / size[1]), (v @ up) / (depth * t)]


def test_front_pieces_are_the_moving_ones_and_their_neighbours():
    from qdem.io.render import frontPieces
    w, pieces = _line()
    centres = [p.refPos.mean(axis=0) for p in pieces]
    speeds = [np.sqrt((p.vel ** 2).sum(axis=1)).max() for p in pieces]
    assert frontPieces(centres, speeds, around=1) == [3, 4, 5, 6]
    assert frontPieces(centres, speeds, around=0) == [4, 5]
    assert frontPieces(centres[::-1], speeds[::-1], around=2) == [0, 1, 2, 3, 4, 5]  # reversed: 7 is the creeping one
    assert frontPieces(centres, np.zeros(8)) == list(range(8))  # nothing moving: everything
    with pytest.raises(ValueError, match="centres"):
        frontPieces(centres, speeds[:3])


def test_camera_follows_the_front():
    """The follow camera has the front pieces (and one either side) filling
    the picture, seen obliquely, and the line's ends out of it."""
    from qdem.io.render import camera
    w, pieces = _line()
    size = (1280, 800)
    front = np.vstack([pieces[k].pos for k in (3, 4, 5, 6)])
    cam = camera(front, 25, -50, size, 1.08, line=w.core.pos, follow=True)
    xy = _project(front, *cam, size)
    assert np.abs(xy).max() < 1 and max(np.ptp(xy, axis=0)) > 1.3   # inside, filling the width or height
    assert np.abs(_project(pieces[0].pos.mean(axis=0)[None], *cam, size)).max() > 1  # the far end: out
    assert np.ptp(_project(w.core.pos, *cam, size)[:, 0]) > 2.5                    # the line: wider than the picture
    d = np.asarray(cam[1]) - cam[0]
    assert np.degrees(np.arcsin(d[2] / np.linalg.norm(d))) == pytest.approx(25)  # the elevation asked
    back = -np.array([np.cos(0.5), np.sin(0.5)])  # from behind the front, 50 deg off the line
    assert np.degrees(np.arccos(d[:2] @ back / np.linalg.norm(d[:2]))) == pytest.approx(50, abs=1.0)  # (the nodes' principal axis)


def test_snapshot_focus_front_fills_the_picture_with_the_front(tmp_path):
    """focus='front': the two stressed, falling blocks of an 8-block line take
    a large part of the picture (red); framed on the whole line they are a
    small part of it."""
    import matplotlib.image as mpimg
    from qdem import render
    w, pieces = _line()
    share = {}
    for name, kw in (("line", {}), ("front", dict(focus="front", around=1, elev=25, azim=-50))):
        path = str(tmp_path / (name + ".png"))
        render.snapshot(w, path, floor=0.0, size=(640, 400), **kw)
        rgb = mpimg.imread(path)[..., :3]
        share[name] = ((rgb[..., 0] > 0.3) & (rgb[..., 0] > 3 * rgb[..., 1]) & (rgb[..., 0] > 3 * rgb[..., 2])).mean()
    assert share["front"] > 0.08 and share["front"] > 1.6 * share["line"]
    with pytest.raises(ValueError, match="focus"):
        render.snapshot(w, str(tmp_path / "x.png"), focus="fastest")
    with pytest.raises(ValueError, match="focus"):
        render.snapshot(w, str(tmp_path / "x.png"), focus=[9])


# ---------------------------------------------------------------------------
# Where the frames go: restarts, two recorders, yade-batch, odd fileBases


def _pvd(path):
    """[(time, file)] of a .pvd, in its order."""
    return [(float(t), f) for t, f in re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', open(path).read())]


def _dropScene(O, base, iterPeriod=50, virtPeriod=0.0, label=""):
    """A small block dropped on a floor, with a VtkRecorder: what a script
    builds again in each process of a restarted run (O.iter from 0)."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O.reset()
    qdem.reset()
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.05), (2, 2, 1)), rubber(young=2e6, viscosity=5.0, radius=0.004),
                  pos=(0, 0, 0.06), vel=(0.2, 0, 0))
    rec = qdem.VtkRecorder(fileBase=base, iterPeriod=iterPeriod, virtPeriod=virtPeriod, label=label)
    O.engines = [ForceResetter(), qdem.QdemEngine(), rec, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    return rec


def test_a_restarted_run_goes_on_with_the_series_of_the_run_before(scene, tmp_path):
    """qdem.loadState in a new process (here: the scene built again, a new
    recorder with the same fileBase): the .pvd keeps the earlier run's frames
    up to the step loaded whose files are still there, drops those the
    earlier run wrote past it (the restart writes its own), and the next frame
    is on the period grid (before: the .pvd listed only the restart's frames,
    the first at step 202).  A run from step 0 starts a new .pvd."""
    O = scene
    base = str(tmp_path / "r-")
    state = str(tmp_path / "r.npz")
    _dropScene(O, base, iterPeriod=50)
    O.run(200, True)
    qdem.saveState(state)
    t200 = qdem.defaultWorld().core.time
    O.run(60, True)                     # frame 250: written past the save, by a run that then died
    os.remove(base + "000050.vtu")      # a frame the user deleted: not listed again
    rec = _dropScene(O, base, iterPeriod=100)
    qdem.loadState(state)
    O.run(110, True)                    # QDEM steps 200..310
    names = [f for _, f in _pvd(tmp_path / "r.pvd")]
    assert names == ["r-000000.vtu", "r-000100.vtu", "r-000150.vtu", "r-000200.vtu", "r-000300.vtu"]
    assert [f for _, f in rec.frames] == names
    times = [t for t, _ in _pvd(tmp_path / "r.pvd")]
    assert times == sorted(times) and times[3] == t200
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".vtu") and int(f[2:8]) % 50]  # on the grid
    _dropScene(O, base, iterPeriod=100)  # a fresh run (step 0) into the same fileBase: a new series
    O.run(110, True)
    assert [f for _, f in _pvd(tmp_path / "r.pvd")] == ["r-000000.vtu", "r-000100.vtu"]


def test_a_run_rewound_by_load_state_rewrites_its_series_in_order(scene, tmp_path):
    """The same recorder through a qdem.loadState to an earlier step (one
    process): frames past it leave the .pvd and are written again, on the
    time grid too (before: the later frames stayed listed ahead of the new
    ones, and virtPeriod wrote nothing until the old last time was passed)."""
    O = scene
    base = str(tmp_path / "w-")
    state = str(tmp_path / "w.npz")
    rec = _dropScene(O, base, iterPeriod=0, virtPeriod=0.0)
    rec.virtPeriod = 60 * O.dt
    O.run(130, True)
    qdem.saveState(state)
    O.run(200, True)
    assert len(rec.frames) == 6         # t = 0, 60, 120, 180, 240, 300 dt
    qdem.loadState(state)
    O.run(70, True)                     # back at 130: frames at 180 dt again (not 130, not 132)
    times = [t for t, _ in _pvd(tmp_path / "w.pvd")]
    assert len(times) == 4 and times == sorted(times)
    np.testing.assert_allclose(np.array(times) / O.dt, [0, 60, 120, 180], atol=1.5)
    assert rec.frames == _pvd(tmp_path / "w.pvd")


def test_o_load_puts_the_recorder_back_with_its_series(scene, tmp_path):
    """O.load of a saved scene brings the recorder back with the frames it
    had at O.save: the loaded run lists those and writes the later ones
    again."""
    O = scene
    base = str(tmp_path / "s-")
    _dropScene(O, base, iterPeriod=50, label="rec")
    O.run(100, True)
    O.save(str(tmp_path / "s.yade.gz"))
    O.run(100, True)
    O.load(str(tmp_path / "s.yade.gz"))
    O.run(60, True)
    rec = [e for e in O.engines if isinstance(e, qdem.VtkRecorder)][0]
    names = ["s-000000.vtu", "s-000050.vtu", "s-000100.vtu", "s-000150.vtu"]
    assert [f for _, f in rec.frames] == names and [f for _, f in _pvd(tmp_path / "s.pvd")] == names


def test_two_recorders_writing_one_pvd_are_refused(scene, tmp_path):
    """'a-' and 'a_' both give a.pvd: each recorder would rewrite it with its
    own frames only.  Refused at the first frame, naming both fileBases; a
    dead one, or recorders with their own .pvd, are fine."""
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber())
    a, b = str(tmp_path / "a-"), str(tmp_path / "a_")
    O.engines = [ForceResetter(), qdem.QdemEngine(), qdem.VtkRecorder(fileBase=a, iterPeriod=10),
                 qdem.VtkRecorder(fileBase=b, iterPeriod=25), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    with pytest.raises(qdem.SetupError) as e:
        O.run(5, True)
    assert repr(a) in str(e.value) and repr(b) in str(e.value) and "own fileBase" in str(e.value)
    assert str(tmp_path / "a.pvd") in str(e.value) and not os.path.exists(tmp_path / "a.pvd")
    O.engines[3].dead = True
    O.engines = O.engines[:3] + [qdem.VtkRecorder(fileBase=str(tmp_path / "b-"), iterPeriod=25)] + O.engines[3:]
    O.run(30, True)
    assert sorted(f for f in os.listdir(tmp_path) if f.endswith(".pvd")) == ["a.pvd", "b.pvd"]


def test_default_file_base_under_yade_batch_holds_the_job_description(scene, tmp_path, monkeypatch):
    """yade-batch runs every line of a table in one directory: with the
    default fileBase each job wrote out/qdem-* and the last one won.  Under
    yade-batch (YADE_BATCH=table:line) the default is out/<description>/qdem-;
    a fileBase given is kept."""
    O = scene
    from yade import ForceResetter, NewtonIntegrator
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.table").write_text("description young\nsoft 2e6\nstiff 5e6\n")
    monkeypatch.delenv("YADE_BATCH", raising=False)
    assert qdem.VtkRecorder().fileBase == "out/qdem-"
    monkeypatch.setenv("YADE_BATCH", "t.table:3")  # how yade-batch starts the job of the table's 3rd line
    rec, mine = qdem.VtkRecorder(iterPeriod=10), qdem.VtkRecorder(fileBase="mine-", iterPeriod=10)
    assert rec.fileBase == "out/stiff/qdem-" and mine.fileBase == "mine-"
    O.tags["description"] = "young=5e6/b"          # readParamsFromTable's tag, when set, is the one used
    assert rec.fileBase == "out/young=5e6_b/qdem-"
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine(), rec, mine, NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(10, True)
    assert sorted(os.listdir(tmp_path / "out" / "young=5e6_b")) == ["qdem-000000.vtu", "qdem-000010.vtu",
                                                                   "qdem.pvd"]
    assert os.path.exists(tmp_path / "mine.pvd")


def _twoFrames(O, recorders):
    from yade import ForceResetter, NewtonIntegrator
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber())
    O.engines = [ForceResetter(), qdem.QdemEngine()] + recorders + [NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(10, True)


def test_file_base_with_tilde_is_in_the_home_directory(scene, tmp_path, monkeypatch):
    """'~/h-' is in the home directory, as in a shell (it made a literal ./~/ before)."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    os.makedirs(tmp_path / "home")
    rec = qdem.VtkRecorder(fileBase="~/h-", iterPeriod=10)
    assert rec.fileBase == str(tmp_path / "home" / "h-")
    _twoFrames(scene, [rec])
    assert sorted(os.listdir(tmp_path / "home")) == ["h-000000.vtu", "h-000010.vtu", "h.pvd"]
    assert os.listdir(tmp_path) == ["home"]


def test_file_base_naming_an_existing_directory_writes_into_it(scene, tmp_path, monkeypatch):
    """An existing directory named without a trailing '/' gets the frames
    inside it, as 'd/' would (they were written beside it, as d000000.vtu)."""
    monkeypatch.chdir(tmp_path)
    os.makedirs(tmp_path / "d")
    rec = qdem.VtkRecorder(fileBase="d", iterPeriod=10)
    _twoFrames(scene, [rec])
    assert sorted(os.listdir(tmp_path / "d")) == ["000000.vtu", "000010.vtu", "frames.pvd"]
    assert os.listdir(tmp_path) == ["d"] and rec.pvdPath() == os.path.join("d", "frames.pvd")
