"""Tetrahedral meshes for QDEM pieces: structured boxes, mesh files read by
meshio (gmsh .msh, .vtu, medit .mesh, ...) and closed triangle surfaces
(OFF/STL/OBJ) meshed with CGAL Mesh_3."""
import numbers
import os

import numpy as np

from . import _core
from .attrs import _isint


def _meshioRead(path, who):
    """meshio.read, with every failure turned into a ValueError naming the
    file.  meshio answers some broken files (a truncated .vtu) by printing the
    reason and calling sys.exit(1), which would end YADE: that is caught too,
    and the printed reason goes into the message."""
    import contextlib
    import io

    import meshio
    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            return meshio.read(path)
    except (Exception, SystemExit) as e:  # meshio raises many types for broken files
        said = " ".join((out.getvalue() + " " + err.getvalue()).split())
        reason = "; ".join(x for x in (str(e) if not isinstance(e, SystemExit) else "", said) if x)
        raise ValueError("%s: cannot read %s: %s" % (who, path, reason or type(e).__name__)) from None


class Mesh:
    """Nodes (N,3) and tetrahedra (T,4) of one piece, in the piece's own frame.
    Checked on construction: NaN, bad indices, inverted or zero-volume tets and
    a non-manifold surface raise ValueError naming the problem."""

    def __init__(self, nodes, tets, check=True):
        raw = np.asarray(nodes)
        if np.iscomplexobj(raw):
            raise ValueError("Mesh: nodes must hold real coordinates, got dtype %s" % raw.dtype)
        try:
            nodes = np.ascontiguousarray(raw, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise ValueError("Mesh: nodes must be numbers of shape (N, 3): %s" % e) from None
        tets = np.asarray(tets)
        if nodes.ndim != 2 or nodes.shape[1] != 3:
            raise ValueError("Mesh: nodes must have shape (N, 3), got %s" % (nodes.shape,))
        if tets.ndim != 2 or tets.shape[1] != 4:
            raise ValueError("Mesh: tets must have shape (T, 4), got %s" % (tets.shape,))
        if not np.issubdtype(tets.dtype, np.integer):
            raise ValueError("Mesh: tets must hold integer node indices, got dtype %s" % tets.dtype)
        if len(nodes) >= 2**31 - 1:
            raise ValueError("Mesh: too many nodes for 32-bit indices")
        if tets.dtype != np.int32 and tets.size:
            # astype(int32) would wrap 2**32 + 5 to node 5: refuse out-of-range indices first
            bad = np.flatnonzero(((tets < 0) | (tets >= len(nodes))).any(axis=1))
            if len(bad):
                t = int(bad[0])
                v = next(int(x) for x in tets[t] if x < 0 or x >= len(nodes))
                raise ValueError("Mesh: tetrahedron %d refers to node %d but the mesh has %d nodes (indices run "
                                 "from 0)" % (t, v, len(nodes)))
        self.nodes = nodes
        self.tets = np.ascontiguousarray(tets, dtype=np.int32)
        if check:
            self.check()

    def check(self):
        """Raise ValueError on NaN, bad index, inverted/zero-volume tet, non-manifold surface."""
        _core.checkMesh(self.nodes, self.tets)
        _core.extractSurface(self.nodes, self.tets)

    @property
    def nNodes(self):
        return len(self.nodes)

    @property
    def nTets(self):
        return len(self.tets)

    def volumes(self):
        """Signed volume of each tetrahedron."""
        return _core.tetVolumes(self.nodes, self.tets)

    def surface(self):
        """Boundary as a dict: triangles (outward), triTet, edges, nodes, tets."""
        return _core.extractSurface(self.nodes, self.tets)

    def bounds(self):
        return self.nodes.min(axis=0), self.nodes.max(axis=0)

    def scaled(self, factor):
        """A copy scaled about the origin (factor: number or 3 numbers)."""
        return Mesh(self.nodes * np.asarray(factor, dtype=float), self.tets.copy(), check=False)

    def __repr__(self):
        return "Mesh(%d nodes, %d tets)" % (self.nNodes, self.nTets)


def splitMesh(mesh):
    """The connected parts of a mesh, one Mesh each (nodes renumbered, in their
    original order), ordered by their first tetrahedron.  Tetrahedra sharing a
    node are one part; for a mesh that passes the manifold check this is the
    same as sharing faces.  addPiece refuses a mesh of several parts (its parts
    would not touch each other): add each part as its own piece::

        for part in qdem.splitMesh(mesh):
            qdem.addPiece(part, mat)
    """
    mesh = asMesh(mesh)
    label = _core.meshParts(mesh.nodes, mesh.tets)
    parts = []
    for k in range(int(label.max()) + 1 if len(label) else 0):
        tets = mesh.tets[label == k]
        used = np.unique(tets)
        remap = -np.ones(len(mesh.nodes), dtype=np.int64)
        remap[used] = np.arange(len(used))
        parts.append(Mesh(mesh.nodes[used], remap[tets].astype(np.int32), check=False))
    return parts


def boxMesh(size=(1.0, 1.0, 1.0), cells=(4, 4, 4), tetsPerCell=6):
    """Structured mesh of a box of ``size`` centred on the origin with ``cells``
    cells per axis.  tetsPerCell: 5, 6 (Kuhn) or 12 (body-centre node, the seed
    paper's cubes: cells=(8,8,8) gives 1,241 nodes and 6,144 tets).

    With even cell counts the mesh is the mirror image of itself about the
    box's three mid-planes for every tetsPerCell (mirror-image nodes carry
    equal lumped masses: a box dropped flat gets no torque from its mesh).
    An odd count along an axis cannot be mirror-symmetric about that axis's
    mid-plane: the middle layer of cells has no symmetric split into these
    tets.  With 6 and 12 the asymmetry is confined to that layer; with 5 the
    alternating split makes the whole mesh differ from its mirror image
    (though equal odd counts keep each face's mass centre at its centre by
    the half-turn symmetry).  Offsets of the bottom face's mass centre for
    2..9 cells: doc/hard_cases.md.  Prefer even counts for drop tests."""
    size = _threeNumbers(size, "size", "a finite number > 0 or 3 of them (x, y, z) [m]")
    if not np.all(np.isfinite(size) & (size > 0)):
        raise ValueError("boxMesh: size must be a finite number > 0 or 3 of them (x, y, z) [m], got %s"
                         % "x".join("%g" % v for v in size))
    cells = _threeNumbers(cells, "cells", "an integer >= 1 or 3 of them (cells along x, y, z)", integral=True)
    if not np.all(cells >= 1):
        raise ValueError("boxMesh: cells must be integers >= 1, got %s" % "x".join("%d" % c for c in cells))
    if not (_isint(tetsPerCell) and int(tetsPerCell) in (5, 6, 12)):
        raise ValueError("boxMesh: tetsPerCell must be 5, 6 or 12, got %r" % (tetsPerCell,))
    tetsPerCell = int(tetsPerCell)
    nx, ny, nz = (int(c) for c in cells)
    nNodes = (nx + 1) * (ny + 1) * (nz + 1) + (nx * ny * nz if tetsPerCell == 12 else 0)
    nTets = nx * ny * nz * tetsPerCell
    if max(nNodes, nTets) > 2**31 - 2:
        raise ValueError("boxMesh: cells=%dx%dx%d with tetsPerCell=%d gives %d nodes and %d tetrahedra, beyond the "
                         "32-bit indices QDEM uses (2^31 - 1); use fewer cells" % (nx, ny, nz, tetsPerCell, nNodes,
                                                                                nTets))
    cellVolume = float(size[0] / nx) * float(size[1] / ny) * float(size[2] / nz)  # Python floats: inf, no warning
    if not (np.isfinite(cellVolume) and cellVolume / tetsPerCell > 1e-290 and cellVolume < 1e290):
        raise ValueError("boxMesh: size %s with cells %dx%dx%d gives cells of volume %g, beyond the range of "
                         "floating point volumes and masses; give the size in metres"
                         % ("x".join("%g" % v for v in size), nx, ny, nz, cellVolume))
    nodes, tets = _core.boxMesh(nx, ny, nz, float(size[0]), float(size[1]), float(size[2]), tetsPerCell)
    return Mesh(nodes, tets, check=False)


def _threeNumbers(value, name, what, integral=False):
    """boxMesh's size / cells: one number (the same along x, y, z) or three."""
    vals = None
    if not isinstance(value, (str, bytes)):
        try:
            a = np.asarray(value, dtype=object)
            if a.ndim == 0:
                a = np.array([value] * 3, dtype=object)
            if a.shape == (3,) and all(isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
                                       for v in a):
                vals = a
        except (TypeError, ValueError):
            vals = None
    if vals is None:
        raise ValueError("boxMesh: %s must be %s, got %r" % (name, what, value))
    if integral:
        if not all(_isint(v) for v in vals):
            raise ValueError("boxMesh: %s must be %s, got %r (no fractions: a count is not rounded)"
                             % (name, what, value))
        return np.array([int(v) for v in vals], dtype=object)
    return np.array([float(v) for v in vals], dtype=float)


# Volume cells of meshio other than linear tetrahedra (meshio's CellBlock.dim
# says 3 for them; this is the fallback for meshio versions without it).
_VOLUME_PREFIXES = ("tetra", "hexahedron", "wedge", "pyramid", "polyhedron", "VTK_LAGRANGE_TETRAHEDRON",
                    "VTK_LAGRANGE_HEXAHEDRON", "VTK_LAGRANGE_WEDGE", "VTK_LAGRANGE_PYRAMID")


def _isVolumeCell(block):
    dim = getattr(block, "dim", None)
    if dim is not None:
        return dim == 3
    return block.type.startswith(_VOLUME_PREFIXES)


def _scaleFactor(scale, who):
    """scale as a float or 3 floats, each finite and > 0."""
    try:
        s = np.asarray(scale, dtype=float) if not isinstance(scale, (str, bytes, bool)) else None
    except (TypeError, ValueError):
        s = None
    if s is None or s.shape not in ((), (3,)) or not np.all(np.isfinite(s)) or not np.all(s > 0):
        raise ValueError("%s: scale must be a finite number > 0 (or 3 of them, one per axis), got %r"
                         % (who, scale))
    return s


def loadMesh(path, fixOrientation=False, scale=1.0):
    """Read a tetrahedral mesh with meshio (gmsh .msh, .vtu, medit .mesh, ...).
    Linear tetrahedra (meshio's 'tetra') make the piece; lower-dimensional
    cells (boundary triangles, lines, vertices: gmsh's tags) are ignored.  A
    file holding other volume cells (hexahedra, wedges, pyramids, quadratic
    'tetra10' ...) is refused rather than loaded in part: re-mesh it into
    linear tetrahedra.  fixOrientation=True flips tets written with the
    opposite orientation convention instead of rejecting them.  scale (a
    number or 3) multiplies the coordinates (0.001 for a file in mm)."""
    scale = _scaleFactor(scale, "loadMesh")
    if not os.path.exists(path):
        raise ValueError("loadMesh: no such file: %s" % path)
    m = _meshioRead(path, "loadMesh")
    other = {}
    for c in m.cells:
        if c.type != "tetra" and _isVolumeCell(c):
            other[c.type] = other.get(c.type, 0) + len(c.data)
    if other:
        raise ValueError("loadMesh: %s holds volume cells that are not linear tetrahedra: %s%s. QDEM uses "
                         "linear 4-node tetrahedra only, and loading the tetrahedra alone would drop part of "
                         "the body. Re-mesh into linear tetrahedra (gmsh: -3 with Mesh.ElementOrder = 1 and "
                         "no Mesh.RecombineAll / recombined or extruded layers; or mesh the closed surface "
                         "with qdem.meshSurface)"
                         % (path, ", ".join("%d %s" % (n, t) for t, n in sorted(other.items())),
                            " (and %d linear tetra)" % sum(len(c.data) for c in m.cells if c.type == "tetra")
                            if any(c.type == "tetra" for c in m.cells) else ""))
    blocks = [c.data for c in m.cells if c.type == "tetra"]
    if not blocks:
        raise ValueError("loadMesh: %s contains no tetrahedra (cell types: %s); a surface or 2-D mesh has no "
                         "volume: mesh the solid into linear tetrahedra (gmsh -3, or qdem.meshSurface for a "
                         "closed surface)"
                         % (path, ", ".join(sorted({c.type for c in m.cells})) or "none"))
    points = np.asarray(m.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError("loadMesh: %s has %d-dimensional points (x, y only); a QDEM piece needs 3-D "
                         "coordinates (x, y, z)" % (path, points.shape[1] if points.ndim == 2 else 0))
    tets = np.concatenate(blocks).astype(np.int64)
    nodes = points * scale
    if tets.min() < 0 or tets.max() >= len(nodes):
        raise ValueError("loadMesh: %s refers to nodes outside 0..%d" % (path, len(nodes) - 1))
    used = np.unique(tets)
    if len(used) < len(nodes):  # drop points that belong to no tet (gmsh geometry points)
        remap = -np.ones(len(nodes), dtype=np.int64)
        remap[used] = np.arange(len(used))
        nodes, tets = nodes[used], remap[tets]
    if np.all(np.isfinite(nodes)):
        flat = [k for k in range(3) if np.ptp(nodes[:, k]) == 0]
        if flat:
            raise ValueError("loadMesh: every node of %s has %s = %g: the mesh is flat (a 2-D mesh written "
                             "with x, y only?) and its tetrahedra have no volume; a QDEM piece needs a 3-D "
                             "tetrahedral mesh" % (path, "xyz"[flat[0]], nodes[0, flat[0]]))
    tets = tets.astype(np.int32)
    if fixOrientation:
        tets, _ = _core.orientPositive(nodes, tets)
    return Mesh(nodes, tets)


def loadSurface(path, scale=1.0):
    """Read a closed triangle surface (OFF, STL, OBJ, PLY, ...) with meshio:
    returns (vertices (V,3), triangles (F,3)), duplicate STL vertices merged."""
    if not os.path.exists(path):
        raise ValueError("loadSurface: no such file: %s" % path)
    scale = _scaleFactor(scale, "loadSurface")
    m = _meshioRead(path, "loadSurface")
    tris = [c.data for c in m.cells if c.type == "triangle"]
    if not tris:
        raise ValueError("loadSurface: %s contains no triangles" % path)
    verts = np.asarray(m.points, dtype=float)[:, :3] * scale
    tris = np.concatenate(tris).astype(np.int64)
    # STL stores every triangle's corners separately: merge equal vertices.
    uniq, inverse = np.unique(np.round(verts, 12), axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)[tris].astype(np.int32)


def meshSurface(surface, cellSize, facetDistance=-1.0, seed=0, scale=1.0, surfaceSize=None):
    """Tetrahedral mesh of the solid bounded by a closed triangle surface, with
    CGAL Mesh_3 to a target element size ``cellSize`` (``surfaceSize``, when
    given, refines the surface triangles alone).  ``surface`` is a file path
    (OFF/STL/OBJ) or a tuple (vertices, triangles)."""
    if not getattr(_core, "haveCgal", False):
        raise RuntimeError("qdem was built without CGAL: install libcgal-dev and rebuild (make build)")
    if isinstance(surface, (str, os.PathLike)):
        verts, tris = loadSurface(surface, scale)
    else:
        verts, tris = surface
        verts = np.asarray(verts, dtype=float) * scale
    nodes, tets = _core.meshClosedSurface(np.ascontiguousarray(verts, dtype=float),
                                          np.ascontiguousarray(tris, dtype=np.int32),
                                          float(cellSize), float(facetDistance), int(seed),
                                          float(surfaceSize) if surfaceSize else -1.0)
    try:
        return Mesh(nodes, tets)
    except ValueError as e:
        if "non-manifold" not in str(e):
            raise
        # Mesh_3 merges the opposite faces of a body thinner than its cells:
        # say so instead of leaving the user with a node number.
        v = np.asarray(verts, dtype=float)[np.asarray(tris, dtype=np.int64)]
        cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        area = 0.5 * np.linalg.norm(cross, axis=1).sum()
        volume = abs(np.einsum("ij,ij->i", v[:, 0] - v.reshape(-1, 3).mean(0), cross).sum()) / 6.0
        skin = float(surfaceSize) if surfaceSize else float(cellSize)
        thickness = 2.0 * volume / area if area > 0 else 0.0
        if thickness < skin:
            raise ValueError("meshSurface: %s. The body is about %.3g thick (2 x volume / surface area) against "
                             "%s %.3g: Mesh_3 merged its opposite faces. Use a cellSize (and surfaceSize) of at "
                             "most about 2 x the thickness, here <= %.3g"
                             % (e, thickness, "surfaceSize" if surfaceSize else "cellSize", skin,
                                2.0 * thickness)) from None
        raise


def asMesh(obj):
    """Mesh from a Mesh, a (nodes, tets) tuple or a mesh file path."""
    if isinstance(obj, Mesh):
        return obj
    if isinstance(obj, (str, os.PathLike)):
        return loadMesh(obj)
    if isinstance(obj, tuple) and len(obj) == 2:
        return Mesh(*obj)
    raise ValueError("expected a qdem.Mesh, a (nodes, tets) tuple or a mesh file path, got %r" % type(obj))
