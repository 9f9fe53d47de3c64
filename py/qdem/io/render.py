"""PNG pictures of QDEM pieces: surfaces coloured by von Mises stress, drawn
with VTK (real depth, lighting, a stress legend, a floor, a camera framed on
what is shown), off screen.

VTK's OpenGL window needs an X display; without one (a batch job, CI) a
private Xvfb is started for the process when the `Xvfb` program is there
(Debian package xvfb, installed by `make deps`) and stopped at exit.  Where
neither works, matplotlib's 3-D painter draws the same picture, less well,
and a warning says why."""
import atexit
import os
import shutil
import subprocess
import warnings

import numpy as np

from ..stress import vonMises

_xvfb = None


def _display():
    """True when an X display is there (starting a private Xvfb if needed)."""
    global _xvfb
    if os.environ.get("DISPLAY"):
        return True
    if _xvfb is not None:
        return _xvfb.poll() is None
    exe = shutil.which("Xvfb")
    if exe is None:
        return False
    r, w = os.pipe()
    _xvfb = subprocess.Popen([exe, "-displayfd", str(w), "-screen", "0", "1600x1200x24", "-nolisten", "tcp"],
                             pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(w)
    with os.fdopen(r) as f:
        num = f.readline().strip()
    if not num:
        _xvfb = None
        return False
    os.environ["DISPLAY"] = ":" + num
    atexit.register(_stopXvfb)
    return True


def _stopXvfb():
    if _xvfb is not None and _xvfb.poll() is None:
        _xvfb.terminate()
        try:
            _xvfb.wait(timeout=5)
        except subprocess.TimeoutExpired:
            _xvfb.kill()


def snapshot(world, path, title="", elev=18, azim=-60, vmax=None, floor=None, pieces=None, size=(1280, 800),
             focus=None, around=2, moving=0.25):
    """Write a PNG of every piece's surface (or only of the piece indices in
    `pieces`, framed on them: a close-up); each triangle takes the von Mises
    stress of its tetrahedron.  vmax fixes the colour scale across frames; a
    floor height draws the floor.  Returns the vmax used.

    focus: the camera follows part of the scene, everything else still drawn
    around it.  "front": the pieces moving now (frontPieces: the fastest piece
    and its neighbours along the line moving at least `moving` times as fast)
    and `around` more on either side; or a list of piece indices.  The camera
    looks from `elev`/`azim` (azimuth measured from the line's axis when the
    drawn pieces form a line) and the colour scale is the focused pieces'."""
    core = world.core
    vm = vonMises(core.stress())
    tris, colors = [], []
    shown = list(range(core.nPieces) if pieces is None else pieces)
    surf = {p: core.pieceSurface(p) for p in shown}
    for p in shown:
        tris.append(surf[p]["triangles"])
        colors.append(vm[surf[p]["triTet"]])
    framed = None
    if focus is not None:
        if isinstance(focus, str):
            if focus != "front":
                raise ValueError("qdem.render.snapshot: focus=%r; give focus='front' or a list of piece indices"
                                 % (focus,))
            ps = [world.pieces[p] for p in shown]
            speeds = [float(np.sqrt((p.vel ** 2).sum(axis=1)).max()) for p in ps]
            focus = [shown[i] for i in frontPieces([p.refPos.mean(axis=0) for p in ps], speeds, around, moving)]
        focus = [int(p) for p in focus]
        if not focus or any(p not in surf for p in focus):
            raise ValueError("qdem.render.snapshot: focus=%s must name drawn pieces (0..%d%s)"
                             % (focus, core.nPieces - 1, "" if pieces is None else ", within pieces="))
        framed = np.unique(np.concatenate([surf[p]["triangles"].ravel() for p in focus]))
        if vmax is None:
            vmax = float(np.max(np.concatenate([vm[surf[p]["triTet"]] for p in focus])))
    return surfacePlot(core.pos, np.vstack(tris), np.concatenate(colors), path, title, elev, azim, vmax, floor,
                       fit=pieces is not None or framed is not None, size=size, frame=framed)


def frontPieces(centres, speeds, around=2, moving=0.25):
    """Indices of the pieces at a propagation front, in their order along the
    line: the fastest piece, its neighbours on either side (in a row) moving
    at least `moving` times as fast, and `around` more pieces on either side.
    `centres` order the pieces along the line (their projection on the
    centres' principal axis; give reference centres: fallen pieces keep their
    place); `speeds` are each piece's fastest node speed.  Nothing moving:
    every piece."""
    c = np.asarray(centres, float)
    v = np.asarray(speeds, float)
    if len(c) != len(v) or len(c) == 0:
        raise ValueError("frontPieces: %d centres for %d speeds" % (len(c), len(v)))
    if len(c) > 1:
        w, V = np.linalg.eigh(np.cov((c - c.mean(axis=0)).T))
        along = (c - c.mean(axis=0)) @ V[:, np.argmax(w)]
        order = np.argsort(along if along[0] <= along[-1] else -along, kind="stable")  # from the first piece
    else:
        order = np.arange(1)
    top = float(v.max())
    if not top > 0:
        return [int(i) for i in order]
    s = v[order]
    k = int(np.argmax(s))
    lo = hi = k
    while lo > 0 and s[lo - 1] >= moving * top:
        lo -= 1
    while hi < len(s) - 1 and s[hi + 1] >= moving * top:
        hi += 1
    return [int(i) for i in order[max(0, lo - around):hi + around + 1]]


def surfaceOfTets(tets):
    """Boundary triangles of a tet mesh (faces used by one tet only) and the
    tet owning each: for meshes read back from VTU files."""
    tets = np.asarray(tets)
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    owner = np.tile(np.arange(len(tets)), 4)
    key = np.sort(faces, axis=1)
    _, idx, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    keep = idx[count == 1]
    return faces[keep], owner[keep]


def surfacePlot(X, tris, val, path, title="", elev=18, azim=-60, vmax=None, floor=None, fit=False,
                size=(1280, 800), frame=None):
    """Write a PNG of triangles `tris` over node positions X, coloured by the
    per-triangle values `val` (von Mises stress [Pa]), the camera looking from
    elevation `elev` and azimuth `azim` [deg] at the triangles and framed on
    them (fit=True: tighter, for close-ups), or on the nodes `frame` (indices
    into X: the camera follows those, the rest drawn around them)."""
    vmax = float(vmax or max(float(np.max(val)), 1e-30))
    X, tris, val = np.asarray(X, float), np.asarray(tris), np.asarray(val, float)
    ext = np.ptp(X[np.unique(tris)][:, :2], axis=0)
    if frame is None and size == (1280, 800) and max(ext) > 4 * max(min(ext), 1e-300):
        size = (1600, 640)  # a long line of pieces: a wide picture
    try:
        ok = _display()
        if ok:
            _vtkPlot(X, tris, val, path, title, elev, azim, vmax, floor, fit, size, frame)
            return vmax
        why = "no X display and no Xvfb (apt-get install xvfb)"
    except ImportError:
        why = "VTK's Python module is missing (apt-get install python3-vtk9)"
    warnings.warn("qdem.render: %s; drawing %s with matplotlib instead" % (why, path), RuntimeWarning)
    _matplotlibPlot(X, tris, val, path, title, elev, azim, vmax, floor, fit, frame)
    return vmax


def _vtkPlot(X, tris, val, path, title, elev, azim, vmax, floor, fit, size, frame):
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.vtkCommonCore import vtkLookupTable, vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkFiltersCore import vtkPolyDataNormals
    from vtkmodules.vtkFiltersSources import vtkPlaneSource
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
    from vtkmodules.vtkRenderingCore import (vtkActor, vtkLight, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow,
                                             vtkTextActor, vtkWindowToImageFilter)
    import vtkmodules.vtkRenderingFreeType  # noqa: F401  (text)
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL back end)

    used = np.unique(tris)
    lo, hi = X[used].min(axis=0), X[used].max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    poly = vtkPolyData()
    pts = vtkPoints()
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(X), deep=True))
    poly.SetPoints(pts)
    cells = vtkCellArray()
    cells.SetData(ns.numpy_to_vtkIdTypeArray(np.arange(0, 3 * len(tris) + 1, 3, dtype=np.int64), deep=True),
                  ns.numpy_to_vtkIdTypeArray(np.ascontiguousarray(tris, dtype=np.int64).ravel(), deep=True))
    poly.SetPolys(cells)
    s = ns.numpy_to_vtk(np.ascontiguousarray(val), deep=True)
    s.SetName("von Mises")
    poly.GetCellData().SetScalars(s)
    normals = vtkPolyDataNormals()  # smooth shading across faces, sharp at the pieces' edges
    normals.SetInputData(poly)
    normals.SetFeatureAngle(40)
    normals.SplittingOn()
    normals.ConsistencyOn()
    lut = vtkLookupTable()
    lut.SetHueRange(0.667, 0.0)  # blue (no stress) to red (vmax)
    lut.SetTableRange(0, vmax)
    lut.Build()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(0, vmax)
    mapper.SetScalarModeToUseCellData()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetAmbient(0.2)
    prop.SetDiffuse(0.8)
    prop.SetSpecular(0.25)
    prop.SetSpecularPower(30)
    ren = vtkRenderer()
    ren.AddActor(actor)
    ren.GradientBackgroundOn()
    ren.SetBackground(0.93, 0.95, 0.98)
    ren.SetBackground2(0.62, 0.70, 0.80)
    if floor is not None:  # a floor around what is shown: its own size plus its height each way
        pad = 0.1 * (hi - lo) + max(hi[2] - floor, 0.2 * span)
        plane = vtkPlaneSource()
        plane.SetOrigin(lo[0] - pad[0], lo[1] - pad[1], floor)
        plane.SetPoint1(hi[0] + pad[0], lo[1] - pad[1], floor)
        plane.SetPoint2(lo[0] - pad[0], hi[1] + pad[1], floor)
        pm = vtkPolyDataMapper()
        pm.SetInputConnection(plane.GetOutputPort())
        pa = vtkActor()
        pa.SetMapper(pm)
        pa.GetProperty().SetColor(0.78, 0.76, 0.72)
        pa.GetProperty().SetAmbient(0.3)
        ren.AddActor(pa)
    bar = vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(" ")  # the title sits left of the bar (vtkScalarBarActor puts it over the labels)
    bar.SetLabelFormat("%.3g")
    bar.SetNumberOfLabels(5)
    bar.SetOrientationToHorizontal()  # along the bottom edge: the pieces keep the width
    bar.SetWidth(0.5)
    bar.SetHeight(0.11)
    bar.SetPosition(0.25, 0.015)
    bar.SetTextPositionToSucceedScalarBar()  # labels and title above the bar, apart
    bar.UnconstrainedFontSizeOn()
    for t, fs in ((bar.GetTitleTextProperty(), 16), (bar.GetLabelTextProperty(), 15)):
        t.SetColor(0.1, 0.1, 0.1)
        t.SetFontSize(fs)
        t.ShadowOff()
        t.ItalicOff()
        t.BoldOff()
    ren.AddActor2D(bar)
    legend = vtkTextActor()
    legend.SetInput("von Mises stress [Pa]")
    legend.GetTextProperty().SetFontSize(17)
    legend.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    legend.GetTextProperty().SetJustificationToRight()
    legend.SetDisplayPosition(int(0.24 * size[0]), int(0.03 * size[1]))
    ren.AddActor2D(legend)
    if title:
        text = vtkTextActor()
        text.SetInput(title)
        text.GetTextProperty().SetFontSize(22)
        text.GetTextProperty().SetColor(0.1, 0.1, 0.1)
        text.SetDisplayPosition(20, size[1] - 40)
        ren.AddActor2D(text)
    for position, intensity in (((-1, 1, 1), 0.55), ((1, 0.3, 0.6), 0.35)):  # key and fill lights
        light = vtkLight()
        light.SetLightTypeToCameraLight()
        light.SetPosition(*position)
        light.SetIntensity(intensity)
        ren.AddLight(light)
    setCamera(ren.GetActiveCamera(), *camera(X[used] if frame is None else X[frame], elev, azim, size,
                                             1.08 if fit else 1.15, line=X[used], follow=frame is not None))
    ren.ResetCameraClippingRange()
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(8)
    win.AddRenderer(ren)
    win.SetSize(*size)
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    png = vtkPNGWriter()
    tmp = path + ".tmp.png"
    png.SetFileName(tmp)
    png.SetInputConnection(grab.GetOutputPort())
    png.Write()
    win.Finalize()
    os.replace(tmp, path)


def camera(P, elev, azim, size, margin, viewAngle=30.0, line=None, follow=False):
    """The camera (focal point, position, view-up, view angle [deg]) looking
    at the points P from elevation/azimuth [deg], at the nearest distance
    where all of them are inside the picture in perspective (with a margin,
    above the colour legend): they fill it.  When the points `line` (default P) form an elongated set
    (a domino line, its points in order), the azimuth is taken from its long
    axis (azim -60 = from 60 deg off the line, on the side of its end) and
    the elevation is kept low; a camera that follows part of the line
    (`follow`) keeps the elevation asked and looks from the side of the
    line's start: from behind a front moving along it, over what has fallen,
    not through the pieces still standing ahead."""
    P = np.asarray(P, float)
    L = P if line is None else np.asarray(line, float)
    centre = 0.5 * (P.min(axis=0) + P.max(axis=0))
    xy = L[:, :2] - L[:, :2].mean(axis=0)
    w, V = np.linalg.eigh(np.cov(xy.T)) if len(L) > 2 else (np.ones(2), np.eye(2))
    lengths = np.ptp(xy @ V, axis=0)  # along the set's principal axes: a diagonal line is a line too
    if len(L) > 2 and max(lengths) > 3 * max(min(lengths), 1e-300):
        long_ = V[:, np.argmax(lengths)]
        if (L[-1, :2] - L[0, :2]) @ long_ < 0:
            long_ = -long_  # along the line, from its first point to its last
        if follow:
            long_ = -long_  # from behind what is followed: the pieces ahead do not hide it
        else:
            elev = min(elev, 12.0)
        azim = azim + np.degrees(np.arctan2(long_[1], long_[0]))
    e, a = np.radians(elev), np.radians(azim)
    d = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])  # towards the camera
    right = np.cross((0.0, 0.0, 1.0), d)
    right /= np.linalg.norm(right)
    up = np.cross(d, right)
    rel = P - centre
    half_w = 0.5 * np.ptp(rel @ right) * margin
    half_h = 0.5 * np.ptp(rel @ up) * margin / 0.84  # the colour legend takes the bottom
    depth = 0.5 * np.ptp(rel @ d)
    tv = np.tan(np.radians(viewAngle) / 2)
    th = tv * size[0] / size[1]
    dist = max(half_w / th, half_h / tv) + depth  # fits: every point no nearer than the box's centre
    focal = centre - 0.08 * half_h / margin * up  # lift the picture's centre above the legend

    def fits(dist):  # in perspective: inside the picture, above the legend (the bottom 20 %)
        v = rel + (centre - focal) - dist * d
        depth = -(v @ d)
        if depth.min() <= 0:
            return False
        x, y = (v @ right) / (depth * th), (v @ up) / (depth * tv)
        return np.abs(x).max() <= 1 / margin and y.max() <= 1 / margin and y.min() >= -0.8 / margin

    near = 0.0
    for _ in range(40):  # the nearest distance that fits: the points fill the picture
        mid = 0.5 * (near + dist)
        near, dist = (near, mid) if fits(mid) else (mid, dist)
    return focal, focal + dist * d, up, viewAngle


def setCamera(cam, focal, position, up, viewAngle):
    cam.SetFocalPoint(*focal)
    cam.SetPosition(*position)
    cam.SetViewUp(*up)
    cam.SetViewAngle(viewAngle)


def _matplotlibPlot(X, tris, val, path, title, elev, azim, vmax, floor, fit, frame):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    fig = plt.figure(figsize=(9, 5.5))
    ax = fig.add_subplot(111, projection="3d")
    poly = Poly3DCollection(X[tris], linewidths=0.05, edgecolors=(0, 0, 0, 0.15))
    poly.set_array(val)
    poly.set_cmap("jet")
    poly.set_clim(0, vmax)
    ax.add_collection3d(poly)
    used = X[np.unique(tris) if frame is None else frame]  # (matplotlib does not clip the rest)
    lo, hi = used.min(axis=0), used.max(axis=0)
    span = (hi - lo).max()
    box0, box1 = lo - 0.05 * span, hi + 0.05 * span
    if floor is not None:
        box0[2] = min(box0[2], floor)
    ax.set_xlim(box0[0], box1[0])
    ax.set_ylim(box0[1], box1[1])
    ax.set_zlim(box0[2], box1[2])
    ax.view_init(elev=elev, azim=azim)
    ax.set_box_aspect(tuple(box1 - box0))
    ax.set_axis_off()
    fig.colorbar(poly, ax=ax, shrink=0.6, label="von Mises stress [Pa]")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

__all__ = ["snapshot", "frontPieces", "surfacePlot"]
