"""What ``addPiece`` says about a mesh users bring (doc/meshes.md, "What the
checks say"): elements that cut the piece's stable step far below what its
median element allows (slivers), and a mesh whose size, against its
material and the scene, looks like millimetres."""
import math
import os
import re
import sys
import warnings

import numpy as np

#: addPiece warns when a piece's stiffest element allows an (undamped) step
#: more than this factor below the step of its median element.  Meshes of
#: good shape sit below it: boxMesh at 1, CGAL's (ballMesh, meshSurface, the
#: shogi pieces) at 2.3 to 4.5, their elements being smaller at a curved
#: surface (refined there until 99 % of the volume is kept) than inside;
#: TetGen without quality at 15 to 10^4 (its slivers).
SLIVER_FACTOR = 5.0

_REMEDIES = ("qdem.improveMesh(mesh) remeshes the slivers away keeping the surface; "
             "qdem.addPiece(..., targetDt=...) adds mass to the few elements that need it (selective mass "
             "scaling, its added mass reported); or mesh again with quality on (TetGen with -q, gmsh's "
             "optimiser: Mesh.Optimize / Mesh.OptimizeNetgen)")


def _userStacklevel():
    """warnings.warn's stacklevel that points at the first frame outside the
    qdem package (the user's addPiece call, through qdem.addPiece or World.addPiece)."""
    here = os.path.dirname(os.path.abspath(__file__))
    f, level = sys._getframe(1), 1
    while f is not None and os.path.dirname(os.path.abspath(f.f_code.co_filename)) == here:
        f, level = f.f_back, level + 1
    return level


def stepFactors(report):
    """(elastic, viscous) factors by which a piece's stiffest element cuts its
    stable step against its median element, from World.pieceStepReport."""
    def ratio(median, worst):
        return median / worst if worst > 0 and math.isfinite(median) else 1.0
    return (ratio(report["medianElastic"], report["stepElastic"]),
            ratio(report["medianViscous"], report["stepViscous"]))


#: The step the advice of warnSlivers aims at: this factor below the median
#: element's (what good CGAL meshes give, doc/meshes.md).
ADVISED_FACTOR = 3.0


def _roundUp(v, digits=2):
    """v rounded up to ``digits`` significant digits, as text."""
    e = math.floor(math.log10(v)) - digits + 1
    return "%.*f" % (max(0, -e), math.ceil(v / 10.0 ** e) * 10.0 ** e)


def warnSlivers(world, pid, nodes=None, tets=None, materialIndex=None, density=None):
    """RuntimeWarning when piece ``pid``'s worst elements cut its stable step
    more than SLIVER_FACTOR below its median element's (undamped steps, the
    shape's measure; with viscosity the cut is up to its square, both are
    named); returns World.pieceStepReport's dict.  Given the piece's placed
    ``nodes``, ``tets``, its material's index and ``density``, the warning
    names the ``targetDt`` that brings the step within ADVISED_FACTOR of the
    median element's and the mass it adds (thin parts: their elements are
    small, not misshapen, and improveMesh does not enlarge them)."""
    r = world.core.pieceStepReport(pid)
    fe, fv = stepFactors(r)
    if not fe > SLIVER_FACTOR:
        return r
    n = int(r["elementsNearLimit"])
    ids = ", ".join(str(i) for i in r["elements"]) + (", ..." if n > len(r["elements"]) else "")
    viscous = r["stepViscous"] < r["stepElastic"]
    advice = ""
    if nodes is not None and materialIndex is not None and density:
        median = min(r["medianElastic"], r["medianViscous"])
        if math.isfinite(median) and median > 0:
            target = float(_roundUp(median / ADVISED_FACTOR, 4))  # as printed: at least median / 3
            added = np.asarray(world.core.massScaling(nodes, tets, materialIndex, target))
            x = np.asarray(nodes, dtype=float)[np.asarray(tets)]
            own = density * float(np.abs(np.einsum("ij,ij->i", x[:, 1] - x[:, 0], np.cross(
                x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]))).sum()) / 6.0
            frac = float(added.sum()) / own
            advice = (" qdem.addPiece(..., targetDt=%s%s) brings its step to %.3g x below the median element's "
                      "by adding %.3g kg, %.3g %% of its mass, to the %d elements that need it;"
                      % (_roundUp(target, 4), ", maxAddedMass=%s" % _roundUp(1.05 * frac) if frac > 0.01 else "", ADVISED_FACTOR,
                         float(added.sum()), 100 * frac, int(np.count_nonzero(added))))
    warnings.warn(
        "qdem.addPiece: piece %d's worst elements cut its stable step %.3g x below what its median element "
        "allows: %.3g s instead of %.3g s%s. %d element%s within 2x of that step (tetrahedra %s of the mesh, "
        "smallest step first), the worst of shape quality %.3g (min height / longest edge; a regular "
        "tetrahedron has 0.816). Remedies:%s %s."
        % (pid, fe, r["stepElastic"], r["medianElastic"],
           " (with the material's viscosity %.3g x: %.3g s instead of %.3g s)" % (fv, r["stepViscous"],
                                                                             r["medianViscous"]) if viscous else "",
           n, " lies" if n == 1 else "s lie", ids, r["worstQuality"], advice, _REMEDIES),
        RuntimeWarning, stacklevel=_userStacklevel())
    return r


# -- units --------------------------------------------------------------------

def _medianEdge(nodes, tets, cap=20000):
    """Median edge length of (up to ``cap`` evenly strided) tetrahedra."""
    t = tets if len(tets) <= cap else tets[np.linspace(0, len(tets) - 1, cap).astype(np.int64)]
    x = nodes[t]  # (T, 4, 3)
    e = [np.linalg.norm(x[:, b] - x[:, a], axis=1) for a in range(4) for b in range(a + 1, 4)]
    return float(np.median(np.concatenate(e)))


def _sceneSpheres(cap=20000):
    """Median radius of the YADE spheres among the first ``cap`` bodies of O.bodies, or None."""
    try:
        from yade import O  # (lazy: the model runs without YADE; inside YADE, its scene's spheres)
        radii = []
        for k, b in enumerate(O.bodies):
            if k >= cap:
                break
            if b is not None and b.shape is not None and type(b.shape).__name__ == "Sphere":
                radii.append(float(b.shape.radius))
        return float(np.median(radii)) if radii else None
    except Exception:  # outside yade, or a scene without bodies
        return None


def unitsClues(world, pid, nodes, tets, material):
    """Clues that piece ``pid`` (its placed ``nodes``, ``tets``) is in
    millimetres: (clear, size, clues) with size its largest extent in the
    mesh's units and clues the phrases naming each.  Clear: a body of 10
    units or more whose elements are at least 200x its contact radius (a
    radius chosen for the body in metres: elements of a 0.12 m part are
    mm-sized, the radius too), or one with two of: 50 units or more, 100x the
    other pieces, 1000x the YADE spheres' diameter.  A 30 m boulder with a
    contact radius of 0.5 m (elements 6x the radius) is none of these."""
    ext = float(np.ptp(nodes, axis=0).max()) if len(nodes) else 0.0
    if not ext >= 10:
        return False, ext, []
    clues, weak, strong = ["%.4g-unit coordinates" % ext], int(ext >= 50), False
    r = float(material.radius)
    h = _medianEdge(nodes, tets)
    if r > 0 and h / r >= 200:
        strong = True
        clues.append("elements of median edge %.3g beside a contact radius of %.3g m, %.0fx smaller" % (h, r, h / r))
    others = [float(np.ptp(np.asarray(p.refPos), axis=0).max()) for p in world.pieces if p.id != pid]
    if others:
        lo = float(np.median(others))
        if lo > 0 and ext / lo >= 100:
            weak += 1
            clues.append("beside pieces of %.3g m" % lo)
    rs = _sceneSpheres()
    if rs and ext / (2 * rs) >= 1000:
        weak += 1
        clues.append("beside spheres of radius %.3g m" % rs)
    return strong or weak >= 2, ext, clues


def unitsAdvice(ext):
    """How to load a mesh in millimetres."""
    return ("load it with qdem.loadMesh(path, scale=0.001) (a Mesh in hand: mesh.scaled(0.001); a surface: "
            "qdem.meshSurface(..., scale=0.001)), which makes it a %.3g m body" % (0.001 * ext))


def warnUnits(world, pid, nodes, tets, material):
    """RuntimeWarning when the piece clearly looks like millimetres
    (unitsClues); returns (clear, note): the phrase a later refusal of its
    placement adds ('' for a body under 10 units)."""
    clear, ext, clues = unitsClues(world, pid, nodes, tets, material)
    if clear:
        note = "the mesh looks like millimetres (%s): %s" % ("; ".join(clues), unitsAdvice(ext))
        warnings.warn("qdem.addPiece: piece %d: %s. QDEM's lengths are metres." % (pid, note), RuntimeWarning,
                      stacklevel=_userStacklevel())
        return True, note
    if ext >= 10:
        return False, ("if the mesh is in millimetres (%.4g-unit coordinates, a %.4g m body as given), %s"
                       % (ext, ext, unitsAdvice(ext)))
    return False, ""


def thickness(nodes):
    """The body's smallest extent across its principal axes [m] (a plate's
    thickness, whatever its orientation)."""
    x = np.asarray(nodes, dtype=float)
    if len(x) < 4:
        return 0.0
    x = x - x.mean(axis=0)
    _, vecs = np.linalg.eigh(x.T @ x)
    return float(np.ptp(x @ vecs[:, 0]))


def warnRadius(pid, nodes, tets, material):
    """RuntimeWarning when the material's contact radius is more than half
    the piece's thickness: its contact surface lies ``radius`` outside the
    mesh, so the piece collides as a body 2 r thicker than its mesh, and
    pieces side by side touch 2 r apart (the seed's radius, 0.04 m, belongs
    to its 766x pieces, not to real-size ones)."""
    r, t = float(material.radius), thickness(nodes)
    if not (t > 0 and r > 0.5 * t):
        return
    h = _medianEdge(nodes, tets)
    warnings.warn(
        "qdem.addPiece: piece %d: the contact radius %.3g m is %.2gx the piece's thickness %.3g m. Its contact "
        "surface lies %.3g m outside the mesh: it collides as a body %.3g m thick, pieces touch %.3g m apart "
        "and rest %.3g m above a floor. Scale the radius with the body: about its element size (median edge "
        "%.3g m) or less, QdemMat(radius=...); the contact stiffness 2 E r follows it (doc/getting_started.md, "
        "choosing parameters)." % (pid, r, r / t, t, r, t + 2 * r, 2 * r, r, h),
        RuntimeWarning, stacklevel=_userStacklevel())


_START_INSIDE = re.compile(r"^piece (\d+) starts inside obstacle")


def explainRefusal(world, error):
    """``error`` (a refusal of the start overlap check) with the units note of
    the piece it names, or None when there is nothing to add: a mesh that
    looks like millimetres is named first, the placement refusal after."""
    m = _START_INSIDE.match(str(error))
    if not m:
        return None
    pid = int(m.group(1))
    clear, note = getattr(world.pieces[pid], "_unitsNote", (False, "")) if pid < len(world.pieces) else (False, "")
    if not note:
        return None
    if clear:
        return "piece %d: %s. (As given, in metres: %s.)" % (pid, note, str(error))
    return "%s. But %s." % (str(error), note)
