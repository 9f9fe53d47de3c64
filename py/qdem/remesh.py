"""Sliver removal from a tetrahedral mesh a user brings (TetGen, gmsh, a
scanner's pipeline): ``improveMesh`` remeshes it with CGAL's tetrahedral
isotropic remeshing while keeping its boundary surface, and says what it
kept.  See doc/meshes.md, "Remedies and what they cost"."""
import time

import numpy as np

from . import _core
from .mesh import Mesh, asMesh


def elementSizes(nodes, tets):
    """The length that sets each element's explicit stable step:
    h_e = 1 / sqrt(sum_a |grad N_a|^2) = 1 / sqrt(sum_a 1/H_a^2), with H_a
    the tet's height over the face opposite node a (|grad N_a| = 1/H_a).

    The element's highest frequency with its lumped mass rho V/4 per node
    obeys omega^2 <= 4 (lambda + 2 mu) / rho * sum_a |grad N_a|^2 (the bound
    qdem's stable step starts from, pkg/world/StableDt.cpp), so the elastic
    step dt = 2/omega is proportional to h_e and the viscous (diffusive)
    step to h_e^2.  A regular tet of edge a has h_e = a / sqrt(6); a sliver
    has h_e near its smallest height."""
    x = np.asarray(nodes, dtype=float)[np.asarray(tets)]
    six = np.abs(np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0]))
    s = np.zeros(len(x))
    for k in range(4):
        a, b, c = (x[:, (k + j) % 4] for j in (1, 2, 3))
        twiceArea = np.linalg.norm(np.cross(b - a, c - a), axis=1)
        s += (twiceArea / six) ** 2  # 1 / H_k^2, H_k = 6V / (2 area)
    return 1.0 / np.sqrt(s)


def meshQuality(mesh):
    """Figures of a mesh's worst elements, as improveMesh reports them:
    stepFactor = median(h_e) / min(h_e) (how many times the worst element
    cuts the elastic step against the median one; its square for the
    viscous step), worstHeightRatio = min over tets of smallest height /
    longest edge (0.816 for a regular tet, near 0 for a sliver), volume."""
    mesh = asMesh(mesh)
    he = elementSizes(mesh.nodes, mesh.tets)
    x = mesh.nodes[mesh.tets]
    six = np.abs(np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0]))
    maxArea2 = np.max([np.linalg.norm(np.cross(x[:, (k + 2) % 4] - x[:, (k + 1) % 4],
                                               x[:, (k + 3) % 4] - x[:, (k + 1) % 4]), axis=1) for k in range(4)],
                      axis=0)
    longest = np.max([np.linalg.norm(x[:, i] - x[:, j], axis=1) for i in range(4) for j in range(i + 1, 4)], axis=0)
    return {"stepFactor": float(np.median(he) / he.min()), "worstHeightRatio": float((six / maxArea2 / longest).min()),
            "medianElementSize": float(np.median(he)), "volume": float(six.sum() / 6.0)}


def improveMesh(mesh, cellSize=None, iterations=8, featureAngle=40.0, maxVolumeChange=0.01, maxDeviation=0.25,
                verbose=False):
    """A sliver-free remesh of a tetrahedral mesh, keeping its boundary surface.

    Slivers (tets whose height is tiny against their edges, which TetGen
    without its quality switch and scanned-surface pipelines leave) set the
    explicit stable step through their highest frequency: a worst element
    100x thinner than the median one cuts the elastic step 100x and the
    viscous one 10,000x.  improveMesh remeshes the whole mesh with CGAL's
    tetrahedral isotropic remeshing (edge splits, collapses, flips and
    smoothing towards a uniform edge length ``cellSize``) and returns a new
    Mesh whose elements are near-regular.

    What it keeps: the boundary vertices move only within the surface (one
    smooth patch per region between feature edges, and moved back onto the
    input surface at the end); feature edges, where the outward normals of
    two boundary triangles turn by more than ``featureAngle`` degrees, stay
    where they are (split or merged along themselves only) and their corners
    stay put.  The volume change is refused above ``maxVolumeChange``
    (relative) and the surface deviation above ``maxDeviation`` x cellSize
    (sampled two-sided distance between the surfaces, at vertices and face
    centres), with a ValueError naming the figures.

    cellSize: target edge length [m]; None = the median boundary edge of the
    input (the resolution at which its surface is described).  A smaller
    cellSize gives more elements and a smaller step.
    iterations: CGAL's full remeshing passes (3 passes of flips and smoothing
    follow them); while the worst element still cuts the step by more than
    2.5x against the median one (by elementSizes; up to 3x by qdem's exact
    element frequencies), up to 3 more rounds of 3 passes follow.

    What it does not keep: node and element numbering.  The result has new
    nodes and tets, ``nodeIds`` is None, and per-node data of the input
    (picked nodes, boundary conditions given by index) must be picked again
    by position on the result.

    The returned Mesh carries ``improveReport``, a dict: before / after
    (meshQuality of each: stepFactor, worstHeightRatio, medianElementSize,
    volume), volumeChange (relative), maxDeviation [m] and its ratio to
    cellSize, cellSize, featureEdges, corners, patches (smooth surface
    regions between feature edges), rounds (calls of CGAL's remeshing),
    nTetsBefore, nTets, seconds.  verbose=True prints it."""
    mesh = asMesh(mesh)
    if not getattr(_core, "haveCgal", False):
        raise RuntimeError("improveMesh: qdem was built without CGAL: install libcgal-dev and rebuild (make build)")
    if cellSize is not None and not (np.isfinite(cellSize) and cellSize > 0):
        raise ValueError("improveMesh: cellSize must be a finite length > 0 [m] (or None for the median boundary "
                         "edge of the mesh), got %r" % (cellSize,))
    for name, value in (("maxVolumeChange", maxVolumeChange), ("maxDeviation", maxDeviation)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError("improveMesh: %s must be a finite number > 0, got %r" % (name, value))
    if int(iterations) != iterations or not 1 <= iterations <= 1000:
        raise ValueError("improveMesh: iterations must be an integer from 1 to 1000, got %r" % (iterations,))
    mesh.check()
    before = meshQuality(mesh)
    t0 = time.perf_counter()
    r = _core.remeshTets(mesh.nodes, mesh.tets, float(cellSize) if cellSize else -1.0, int(iterations),
                         float(featureAngle))
    seconds = time.perf_counter() - t0
    out = Mesh(r["nodes"], r["tets"])
    after = meshQuality(out)
    h = r["targetEdge"]
    report = {"before": before, "after": after, "volumeChange": after["volume"] / before["volume"] - 1.0,
              "maxDeviation": r["maxDeviation"], "deviationPerCell": r["maxDeviation"] / h, "cellSize": h,
              "featureEdges": len(r["featureEdges"]), "corners": len(r["corners"]), "patches": r["patches"],
              "rounds": r["rounds"], "nTetsBefore": mesh.nTets, "nTets": out.nTets, "seconds": seconds}
    if verbose:
        print(_describe(report))
    if abs(report["volumeChange"]) > maxVolumeChange:
        raise ValueError("improveMesh: the remeshed volume differs from the input's by %.3g %% (allowed %.3g %%, "
                         "maxVolumeChange): the surface is too coarse or too curved for cellSize %.3g m. Use a smaller "
                         "cellSize, or a smaller featureAngle to keep more of its edges. %s"
                         % (100 * report["volumeChange"], 100 * maxVolumeChange, h, _describe(report)))
    if report["deviationPerCell"] > maxDeviation:
        raise ValueError("improveMesh: the remeshed surface departs from the input's by up to %.3g m = %.3g x "
                         "cellSize (allowed %.3g x, maxDeviation): use a smaller cellSize, or a smaller featureAngle "
                         "to keep more of its edges. %s" % (r["maxDeviation"], report["deviationPerCell"], maxDeviation,
                                                          _describe(report)))
    out.improveReport = report
    return out


def _describe(r):
    b, a = r["before"], r["after"]
    return ("improveMesh: %d -> %d tets at cellSize %.3g m in %.2f s (%d rounds); worst element cuts the step %.3gx -> %.3gx "
            "against the median (height/longest edge %.3g -> %.3g); volume %+.3g %%; surface within %.3g m "
            "(%.3g x cellSize); %d feature edges, %d corners, %d surface patches kept"
            % (r["nTetsBefore"], r["nTets"],
               r["cellSize"], r["seconds"], r["rounds"], b["stepFactor"], a["stepFactor"], b["worstHeightRatio"],
               a["worstHeightRatio"], 100 * r["volumeChange"], r["maxDeviation"], r["deviationPerCell"],
               r["featureEdges"], r["corners"], r["patches"]))
