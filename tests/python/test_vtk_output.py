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
from qdem.vtu import readVtu


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
    from qdem.vtu import writeVtu
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
    from qdem.render import frontPieces
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
    from qdem.render import camera
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
