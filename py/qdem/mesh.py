"""Tetrahedral meshes for QDEM pieces: structured boxes, mesh files read by
meshio (gmsh .msh, .vtu, medit .mesh, ...) and closed triangle surfaces
(OFF/STL/OBJ) meshed with CGAL Mesh_3."""
import contextlib
import io
import numbers
import os
import struct
import warnings

import numpy as np

from . import _core
from .attrs import _isint


def _meshioRead(path, who):
    """meshio.read, with every failure turned into a ValueError naming the
    file.  meshio answers some broken files (a truncated .vtu) by printing the
    reason and calling sys.exit(1), which would end YADE: that is caught too,
    and the printed reason goes into the message."""
    import meshio  # (lazy: meshio is needed only when a file is read)
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
    Checked on construction: NaN, bad indices, inverted or zero-volume tets, a
    non-manifold surface, coincident nodes inside one part (an unmerged
    interface: a crack) and coordinates so far from the origin that double
    rounding distorts the elements raise ValueError naming the problem.

    nodeIds (N,) or None: the index in the mesh file of each node (loadMesh
    sets it: a file's points that no tetrahedron uses are dropped, so node i
    need not be the file's point i).  A piece added from this mesh gets
    originalNodeIds in that numbering; None means the mesh's own indices.

    regions (T,) or None: an integer label per tetrahedron, e.g. its gmsh
    physical group or medit reference (loadMesh) or its CAD solid (meshCad);
    ``qdem.splitMesh(mesh, by='region')`` gives one mesh per label, for a
    piece of each material (doc/meshes.md, "Regions and bimaterial parts")."""

    surfaceVolume = None
    """Volume enclosed by the surface a mesh was made from [m^3] (meshSurface
    sets it; None for other meshes)."""
    volumeKept = None
    """The mesh's volume over surfaceVolume (meshSurface; None for other
    meshes): 0.99 means the piece is 1 % lighter than the solid."""
    meshReport = None
    """meshSurface's report (a dict: the sizes of the last meshing, how many
    meshings the volume took, the thinnest part found, ...; None for other meshes)."""
    improveReport = None
    """improveMesh's report (a dict: worst element and step factor before and
    after, volume change, surface deviation, time; None for other meshes)."""

    def __init__(self, nodes, tets, check=True, nodeIds=None, regions=None):
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
        self.nodeIds = _nodeIds(nodeIds, len(nodes))
        self.regions = _regions(regions, len(self.tets))
        if check:
            self.check()

    def check(self):
        """Raise ValueError on NaN, bad index, inverted/zero-volume tet, coincident
        nodes in one part, coordinates too far from the origin, non-manifold surface."""
        _checkPrecision(self.nodes, self.tets)  # first: far out, tets can come out flat or inverted
        _core.checkMesh(self.nodes, self.tets)
        _checkCoincidentNodes(self.nodes, self.tets, self.nodeIds)
        _core.extractSurface(self.nodes, self.tets)

    def originalIds(self, order):
        """The ids a piece reports as originalNodeIds for its nodes taken in
        ``order`` (indices into this mesh's nodes, e.g. addPiece's reordering):
        the file's point indices for a mesh from loadMesh, else ``order``."""
        order = np.asarray(order)
        return order if self.nodeIds is None else self.nodeIds[order]

    @property
    def nNodes(self):
        """Number of nodes."""
        return len(self.nodes)

    @property
    def nTets(self):
        """Number of tetrahedra."""
        return len(self.tets)

    def volumes(self):
        """Signed volume of each tetrahedron."""
        return _core.tetVolumes(self.nodes, self.tets)

    def surface(self):
        """Boundary as a dict: triangles (outward), triTet, edges, nodes, tets."""
        return _core.extractSurface(self.nodes, self.tets)

    def bounds(self):
        """Bounding box: (lowest corner, highest corner) of the nodes [m]."""
        return self.nodes.min(axis=0), self.nodes.max(axis=0)

    def scaled(self, factor):
        """A copy scaled about the origin (factor: number or 3 numbers)."""
        return Mesh(self.nodes * np.asarray(factor, dtype=float), self.tets.copy(), check=False,
                    nodeIds=self.nodeIds, regions=self.regions)

    def __repr__(self):
        return "Mesh(%d nodes, %d tets)" % (self.nNodes, self.nTets)


def _nodeIds(ids, n):
    """Mesh.nodeIds: None, or one integer per node (its point index in the file)."""
    if ids is None:
        return None
    ids = np.asarray(ids)
    if ids.shape != (n,) or (n and not np.issubdtype(ids.dtype, np.integer)):
        raise ValueError("Mesh: nodeIds must be one integer per node (%d), got shape %s dtype %s"
                         % (n, ids.shape, ids.dtype))
    return ids.astype(np.int64)


def _regions(regions, nTets):
    """Mesh.regions: None, or one integer label per tetrahedron."""
    if regions is None:
        return None
    r = np.asarray(regions)
    if r.shape != (nTets,) or (nTets and not np.issubdtype(r.dtype, np.integer)):
        raise ValueError("Mesh: regions must be one integer label per tetrahedron (%d), got shape %s dtype %s"
                         % (nTets, r.shape, r.dtype))
    return r.astype(np.int64)


def _fileId(nodeIds, i):
    """How an error names node i: with its file index when that differs."""
    if nodeIds is None or nodeIds[i] == i:
        return "%d" % i
    return "%d (point %d of the file)" % (i, nodeIds[i])


# Rounding of coordinates far from the origin.  A double holds a coordinate of
# magnitude X to within u*X (u = 2^-53), so each node of a mesh written at an
# offset X has already moved by up to u*X before we see it (and moves again at
# every step if the piece is placed there).  For a tetrahedron of size
# s = (6|V|)^(1/3) that changes the volume by a relative c*u*X/s: c = 8 is the
# first-order bound with all twelve roundings aligned, while the largest
# per-tet error measured on boxMesh blocks written at offsets 1e6..1e14 m and
# read back was 1.3..1.9 u*X/s; we take c = 2.  Refusing beyond a 1e-6
# relative volume error means X/s > 4.5e9: 1e6-1e8 m (UTM-like) coordinates
# with elements of 1 m, or of 1 cm at 1e7 m, load; a 0.3 m box at 1e10 m
# (1.4e-5 volume error) or 1e14 m (8 %) is refused.
_ROUNDING_C, _VOLUME_RTOL = 2.0, 1e-6


def _checkPrecision(nodes, tets):
    """Refuse a mesh whose coordinates are so large against its smallest
    element that double rounding distorts element volumes beyond _VOLUME_RTOL;
    only when an offset is the cause (centre farther from the origin than the
    mesh's half extent), since translating is then the fix.  Costs one pass of
    tetVolumes (some ms for 1M tets)."""
    if not len(tets) or not np.isfinite(nodes).all() or tets.min() < 0 or tets.max() >= len(nodes):
        return  # checkMesh names these
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    X = float(np.abs(nodes).max())
    centre, half = 0.5 * (lo + hi), 0.5 * float((hi - lo).max())
    if float(np.abs(centre).max()) <= half:
        return  # near the origin: translating would not help (a degenerate tet is checkMesh's business)
    v = np.abs(_core.tetVolumes(nodes, tets))
    v = v[v > 0]
    s = float(np.cbrt(6.0 * v.min())) if len(v) else 0.0  # all flat: coordinates collapsed by rounding
    err = _ROUNDING_C * 2.0**-53 * X / s if s > 0 else np.inf
    if err > _VOLUME_RTOL:
        raise ValueError(
            "Mesh: coordinates reach %.3g m while the smallest element is %.3g m in size ((6 x volume)^(1/3)): "
            "at that offset (mesh centre (%.10g, %.10g, %.10g)) a double holds a coordinate only to within %.2g m, "
            "which distorts element volumes by about %.2g relative (allowed %g). Translate the mesh near the "
            "origin where it is made (in the mesher or CAD, before writing the file: the file's coordinates "
            "have already lost those digits), e.g. subtract the centre, and place it with "
            "addPiece(mesh, material, pos=centre)"
            % (X, s, centre[0], centre[1], centre[2], 2.0**-53 * X, err, _VOLUME_RTOL))


# Coincident nodes: exact equality.  Duplicates come from copying a node's
# coordinates (an interface meshed twice, a mesher's unmerged seam), so they are
# bit-identical, and text formats write both copies with the same digits.  A
# tolerance would need a length scale (a mesh graded from 1 m to 1 um has
# legitimate node pairs closer than any fixed fraction of its size) and a
# neighbour search instead of one sort; nodes nearly coincident inside a tet
# are already refused as a zero-volume tetrahedron.
def _checkCoincidentNodes(nodes, tets, nodeIds=None):
    """Refuse distinct nodes at identical coordinates inside one connected part:
    an internal crack whose faces pass through each other (contacts inside a
    piece are skipped).  Coincident nodes of different parts (blocks touching
    in one file) are left to addPiece's parts check / splitMesh.  One lexsort,
    O(N log N); the part labels are computed only when duplicates exist."""
    if len(nodes) < 2:
        return
    order = np.lexsort(nodes.T[::-1])
    s = nodes[order]
    if not (s[1:] == s[:-1]).all(axis=1).any():
        return
    node = -np.ones(len(nodes), dtype=np.int64)  # part of each node; -1: in no tet (addPiece refuses those)
    node[tets] = _core.meshParts(nodes, tets)[:, None]
    # sort by part within equal coordinates too, so that same-part twins are neighbours
    order = np.lexsort((node, nodes[:, 2], nodes[:, 1], nodes[:, 0]))
    s, lab = nodes[order], node[order]
    twin = (s[1:] == s[:-1]).all(axis=1) & (lab[1:] == lab[:-1]) & (lab[1:] >= 0)
    k = np.flatnonzero(twin)
    if not len(k):
        return
    pairs = ", ".join("%s and %s at (%.6g, %.6g, %.6g)"
                      % ((_fileId(nodeIds, order[i]), _fileId(nodeIds, order[i + 1])) + tuple(s[i])) for i in k[:3])
    raise ValueError(
        "Mesh: %d pair%s of distinct nodes at identical coordinates in one connected part (nodes %s%s): an "
        "interface left unmerged, i.e. an internal crack. Contacts inside a piece are skipped, so its faces "
        "would pass through each other. Merge the duplicate nodes (gmsh: 'Coherence Mesh;' or "
        "gmsh.model.mesh.removeDuplicateNodes() before writing; with NumPy: u, inv = np.unique(nodes, axis=0, "
        "return_inverse=True); qdem.Mesh(u, inv.ravel()[tets])). If the crack is meant, cut the parts fully "
        "apart and add each with qdem.splitMesh / qdem.addPiece"
        % (len(k), "" if len(k) == 1 else "s", pairs, ", ..." if len(k) > 3 else ""))


def _subMesh(mesh, keep):
    """The tetrahedra ``keep`` (a boolean mask) of a mesh as a Mesh of their
    own: nodes renumbered in their original order, nodeIds (the file's point
    indices) and regions carried."""
    tets = mesh.tets[keep]
    used = np.unique(tets)
    remap = -np.ones(len(mesh.nodes), dtype=np.int64)
    remap[used] = np.arange(len(used))
    ids = np.arange(len(mesh.nodes))[used] if mesh.nodeIds is None else mesh.nodeIds[used]
    return Mesh(mesh.nodes[used], remap[tets].astype(np.int32), check=False, nodeIds=ids,
                regions=None if mesh.regions is None else mesh.regions[keep])


def splitMesh(mesh, by="part"):
    """Split a mesh into meshes of their own.

    by='part' (default): the connected parts, a list of Mesh ordered by their
    first tetrahedron.  Tetrahedra sharing a node are one part; for a mesh
    that passes the manifold check this is the same as sharing faces.
    addPiece refuses a mesh of several parts (its parts would not touch each
    other): add each part as its own piece::

        for part in qdem.splitMesh(mesh):
            qdem.addPiece(part, mat)

    by='region': one Mesh per label of ``mesh.regions`` (gmsh physical
    groups, medit references, CAD solids), as a dict {label: Mesh} in
    increasing label order, for a piece of its own material each::

        mats = {1: steel, 2: rubber}
        for label, sub in qdem.splitMesh(mesh, by='region').items():
            qdem.addPiece(sub, mats[label])

    Pieces are joined only by contact, not bonded: where two regions share an
    interface, the two pieces start pressed into each other by their
    contact reach (doc/meshes.md, "Regions and bimaterial parts").  For a
    bonded part, add the whole mesh as one piece of several materials:
    ``qdem.addPiece(mesh, regionMaterials={1: steel, 2: rubber})``.

    Every sub-mesh keeps the nodes' indices in the file (``Mesh.nodeIds``;
    for a mesh built in memory, its node indices) and the region labels, so
    a piece's ``originalNodeIds`` still name the points of the original."""
    mesh = asMesh(mesh)
    if by == "part":
        label = _core.meshParts(mesh.nodes, mesh.tets)
        parts = [_subMesh(mesh, label == k) for k in range(int(label.max()) + 1 if len(label) else 0)]
        if mesh.nodeIds is None:  # in-memory mesh: as before, parts number their nodes themselves
            for p in parts:
                p.nodeIds = None
        return parts
    if by == "region":
        if mesh.regions is None:
            raise ValueError("splitMesh: the mesh has no regions (Mesh.regions is None): regions come from gmsh "
                             "physical groups or medit references read by qdem.loadMesh, from the solids of a "
                             "CAD file (qdem.meshCad), or Mesh(nodes, tets, regions=labels)")
        return {int(k): _subMesh(mesh, mesh.regions == k) for k in np.unique(mesh.regions)}
    raise ValueError("splitMesh: by must be 'part' or 'region', got %r" % (by,))


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


# Cell data that label a tetrahedron's region, in the order they are looked
# for: gmsh's physical group, medit's reference, the VTK name several
# converters (meshio, FEniCS, ...) write them under.
_REGION_KEYS = ("gmsh:physical", "medit:ref", "CellEntityIds")


def _fileRegions(m):
    """One integer label per tetrahedron (in loadMesh's order: the tetra
    blocks concatenated) from a meshio mesh's cell data, or None when the
    file has none, or labels every tetrahedron 0 (gmsh without physical
    groups)."""
    for key in _REGION_KEYS:
        data = m.cell_data.get(key)
        if data is None:
            continue
        labels = [np.asarray(d).reshape(-1) for c, d in zip(m.cells, data) if c.type == "tetra"]
        if not labels or not all(np.issubdtype(l.dtype, np.number) for l in labels):
            continue
        r = np.concatenate(labels)
        if len(r) and np.all(np.isfinite(r)) and np.all(r == np.round(r)) and np.any(r != 0):
            return r.astype(np.int64)
    return None


def _refuseRepeatedTets(path, tets, regions):
    """A tetrahedron listed twice (same four nodes) would be two elements
    of double stiffness and mass and a face shared by four tets.  gmsh's MSH
    2 format writes an element once per physical group it belongs to, so a
    volume put in two groups gives exactly that: say so."""
    key = np.sort(tets, axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    if not (count > 1).any():
        return
    k = int(first[np.flatnonzero(count > 1)[0]])
    twin = np.flatnonzero((key == key[k]).all(axis=1))
    groups = "" if regions is None else " (regions %s)" % ", ".join("%d" % regions[t] for t in twin)
    raise ValueError("loadMesh: %s lists %d tetrahedra more than once (tetrahedron %d, on points %s of the file, appears %d times%s). "
                     "gmsh's MSH 2 format writes an element once per physical group it belongs to: put each volume "
                     "in one physical group only (or write MSH 4)"
                     % (path, int((count - 1).sum()), k, " ".join("%d" % v for v in tets[k]), len(twin), groups))


def _msh4VolumeGroups(path):
    """{volume entity tag: [physical group tags]} from an MSH 4 file's
    $Entities section (ASCII or binary), or {} for any other file.  meshio
    labels a volume's tetrahedra with the first of its groups only."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"$MeshFormat":
            return {}
        head = f.readline().split()
        if len(head) < 3 or not head[0].startswith(b"4"):
            return {}
        binary, sizeT = head[1] == b"1", int(head[2])
        if binary:
            f.read(4)  # the endianness word (int 1)
        for line in f:
            if line.strip() == b"$Entities":
                break
            if line.strip() in (b"$Nodes", b"$Elements"):
                return {}
        else:
            return {}
        groups = {}
        if not binary:
            counts = [int(v) for v in f.readline().split()[:4]]
            lines = [f.readline().split() for _ in range(sum(counts))]
            for fields in lines[sum(counts[:3]):]:  # volumes: tag, box (6), nPhysical, tags, ...
                n = int(fields[7])
                groups[int(fields[0])] = [int(v) for v in fields[8:8 + n]]
            return groups
        st = {8: "Q", 4: "I"}.get(sizeT)
        if st is None:
            return {}
        size = lambda: struct.unpack("<" + st, f.read(sizeT))[0]  # noqa: E731
        ints = lambda n: list(struct.unpack("<%di" % n, f.read(4 * n)))  # noqa: E731
        counts = [size() for _ in range(4)]
        for dim in range(4):
            for _ in range(counts[dim]):
                tag = ints(1)[0]
                f.read(8 * (3 if dim == 0 else 6))  # the point, or the bounding box
                phys = ints(size())
                if dim > 0:
                    ints(size())  # bounding entities
                if dim == 3:
                    groups[tag] = phys
        return groups


def _refuseVolumesInTwoGroups(path):
    """An MSH 4 volume in more than one physical group: its tetrahedra can
    carry one region label only (meshio keeps the first group and drops the
    volume from the others, silently): say so."""
    try:
        groups = _msh4VolumeGroups(path)
    except (OSError, ValueError, IndexError, struct.error):
        return  # not a readable MSH 4 $Entities section: meshio has read the file, its labels stand
    shared = {v: g for v, g in sorted(groups.items()) if len(g) > 1}
    if shared:
        raise ValueError("loadMesh: %s puts volume%s %s in more than one physical group (%s); a tetrahedron has "
                         "one region label, and the file's other groups would lose %s silently. Put each volume "
                         "in one physical group only (make a group for each material region; "
                         "qdem.splitMesh(mesh, by='region') then gives one Mesh per group)"
                         % (path, "s" if len(shared) > 1 else "", ", ".join("%d" % v for v in shared),
                            "; ".join("volume %d in groups %s" % (v, ", ".join("%d" % t for t in g))
                                      for v, g in shared.items()),
                            "it" if len(shared) == 1 else "them"))


def loadMesh(path, fixOrientation=False, scale=1.0):
    """Read a tetrahedral mesh with meshio (gmsh .msh, .vtu, medit .mesh, ...).
    Linear tetrahedra (meshio's 'tetra') make the piece; lower-dimensional
    cells (boundary triangles, lines, vertices: gmsh's tags) are ignored.  A
    file holding other volume cells (hexahedra, wedges, pyramids, quadratic
    'tetra10' ...) is refused rather than loaded in part: re-mesh it into
    linear tetrahedra.  fixOrientation=True flips tets written with the
    opposite orientation convention instead of rejecting them.  scale (a
    number or 3) multiplies the coordinates (0.001 for a file in mm).

    Points no tetrahedron uses (gmsh writes geometry points) are dropped;
    the returned Mesh's ``nodeIds`` holds each node's index in the file, and
    a piece added from it (or from the path) reports those file indices as
    ``originalNodeIds``: nodes picked by their index in the file (e.g. from
    meshio.read) are found with ``np.isin(piece.originalNodeIds, picked)``.

    Regions: a tetrahedron's gmsh physical group (``gmsh:physical``), medit
    reference (``medit:ref``) or ``CellEntityIds`` (VTK) becomes its label in
    ``Mesh.regions`` (None when the file has none), for
    ``qdem.splitMesh(mesh, by='region')``."""
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
    regions = _fileRegions(m)
    if regions is not None and m.cell_data.get("gmsh:physical") is not None:
        _refuseVolumesInTwoGroups(path)
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
    _refuseRepeatedTets(path, tets, regions)  # (the file's point numbers)
    used = np.unique(tets)  # the file's index of each node we keep (nodeIds)
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
    return Mesh(nodes, tets, nodeIds=used, regions=regions)


class _Faces:
    """A block of faces as meshio gives them (type, data)."""

    def __init__(self, type_, data):
        self.type, self.data = type_, data


def _readOff(path):
    """Points and face blocks of an OFF file (Geomview's format: 'OFF', the
    counts of vertices, faces and edges, the vertices, then each face as its
    corner count and corners; '#' starts a comment; colours after a face are
    ignored).  meshio refuses OFF faces other than triangles ("Can only read
    triangular faces"), while quads are what many exporters write."""
    with open(path) as f:
        lines = [l.split("#", 1)[0].split() for l in f]
    lines = [l for l in lines if l]
    try:
        if not lines or not lines[0][0].endswith("OFF"):
            raise ValueError("it does not start with OFF")
        head = lines[0][1:] or lines[1]  # (the counts on the OFF line, or on the next)
        at = 1 if lines[0][1:] else 2
        nv, nf = int(head[0]), int(head[1])
        # One vertex or face per line; what follows its numbers (colours,
        # normals) is ignored.
        points = np.array([[float(w) for w in l[:3]] for l in lines[at:at + nv]], dtype=float).reshape(nv, 3)
        faces = []
        for l in lines[at + nv:at + nv + nf]:
            k = int(l[0])
            if len(l) < 1 + k:
                raise ValueError("face %d lists fewer than its %d corners" % (len(faces), k))
            faces.append([int(w) for w in l[1:1 + k]])
        if len(faces) != nf:
            raise ValueError("%d faces announced, %d found" % (nf, len(faces)))
    except (ValueError, IndexError) as e:
        raise ValueError("loadSurface: cannot read %s as OFF: %s" % (path, e or "too short")) from None
    blocks = {}
    for face in faces:
        blocks.setdefault(len(face), []).append(face)
    return points, [_Faces("triangle" if k == 3 else "quad" if k == 4 else "polygon%d" % k, np.array(fs))
                    for k, fs in sorted(blocks.items())]


def _faceTriangles(block, verts, path):
    """The triangles of one meshio cell block, as a list of (F,3) arrays.
    Dropping quads or polygons would leave holes (a 'surface is not closed'
    error that blames the file), so they are split: a fan from one corner
    keeps the face's orientation.  Valid for convex faces; a concave quad is
    split along its other diagonal, a non-convex polygon is refused."""
    if block.type == "triangle":
        return [np.asarray(block.data)]
    if not (block.type == "quad" or block.type.startswith("polygon")):
        return []
    data = block.data
    if not (isinstance(data, np.ndarray) and data.ndim == 2):  # polygons of several sizes: group them
        rows = [np.asarray(r) for r in data]
        return [t for k in sorted({len(r) for r in rows})
                for t in _fanTriangles(np.array([r for r in rows if len(r) == k]), verts, path)]
    return _fanTriangles(np.asarray(data), verts, path)


def _fanTriangles(faces, verts, path):
    """Faces (F,k) with k >= 3 corners, fanned from corner 0; a quad whose fan
    turns against the face (concave at corner 1 or 3) is fanned from corner 1."""
    faces = faces.astype(np.int64)
    k = faces.shape[1]
    if k < 3 or not len(faces):
        return []
    if faces.min() < 0 or faces.max() >= len(verts):
        return [faces[:, :3]]  # meshClosedSurface names the bad index
    bad = _againstFace(_fan(faces), verts, faces)
    if k == 4 and bad.any():
        faces[bad] = np.roll(faces[bad], -1, axis=1)
        bad = _againstFace(_fan(faces), verts, faces)
    if bad.any():
        f = faces[int(np.flatnonzero(bad)[0])]
        raise ValueError("loadSurface: %s: a face of %d corners (vertices %s, counted from 0) is not convex, and "
                         "only convex faces are split into triangles. Triangulate the surface when exporting it "
                         "(Blender: Triangulate Faces in the export options, or a Triangulate modifier)"
                         % (path, k, " ".join("%d" % v for v in f)))
    return [_fan(faces).reshape(-1, 3)]


def _fan(faces):
    """(F, k-2, 3): the fan of triangles from corner 0 of each of the faces (F,k)."""
    return np.stack([faces[:, [0, j, j + 1]] for j in range(1, faces.shape[1] - 1)], axis=1)


def _againstFace(fanTris, verts, faces):
    """Per face: does a fan triangle turn against the face's normal (Newell's
    normal, the sum of its corners' cross products)?  Only for finite
    coordinates; NaN is named by meshClosedSurface."""
    p = verts[faces]
    normal = np.cross(p, np.roll(p, -1, axis=1)).sum(axis=1)
    t = verts[fanTris]
    n = np.cross(t[..., 1, :] - t[..., 0, :], t[..., 2, :] - t[..., 0, :])
    with np.errstate(invalid="ignore"):
        return (np.einsum("fjk,fk->fj", n, normal) < 0).any(axis=1)


def loadSurface(path, scale=1.0):
    """Read a closed surface (OFF, STL, OBJ, PLY, ...) with meshio: returns
    (vertices (V,3), triangles (F,3)), duplicate STL vertices merged.  Quads
    (Blender's default OBJ export) and convex polygons are split into
    triangles of the same orientation; lines and points are ignored."""
    if not os.path.exists(path):
        raise ValueError("loadSurface: no such file: %s" % path)
    scale = _scaleFactor(scale, "loadSurface")
    if str(path).lower().endswith(".off"):
        points, cells = _readOff(path)  # (meshio reads triangles only from OFF)
    else:
        m = _meshioRead(path, "loadSurface")
        points, cells = m.points, m.cells
    verts = np.asarray(points, dtype=float)[:, :3] * scale
    tris = [t for c in cells for t in _faceTriangles(c, verts, path)]
    if not tris:
        raise ValueError("loadSurface: %s contains no triangles, quads or polygons (cell types: %s): a closed "
                         "surface is needed" % (path, ", ".join(sorted({c.type for c in m.cells})) or "none"))
    tris = np.concatenate(tris).astype(np.int64)
    # STL stores every triangle's corners separately: merge equal vertices.
    uniq, inverse = np.unique(np.round(verts, 12), axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)[tris].astype(np.int32)


def meshSurface(surface, cellSize, facetDistance=-1.0, seed=0, scale=1.0, surfaceSize=None):
    """Tetrahedral mesh of the solid bounded by a closed triangle surface, with
    CGAL Mesh_3 to a target element size ``cellSize`` (``surfaceSize``, when
    given, refines the surface triangles alone).  ``surface`` is a file path
    (OFF/STL/OBJ) or a tuple (vertices, triangles).

    Parts of the body thinner than the cells (an ear, a fin, measured through
    the body along the surface normals) get cells of half their thickness.
    Sharp edges (dihedral sharper than 60 degrees) are kept, except sets of
    them shorter than the surface size, stray creases of a scan or an
    isosurface that would need elements of their length: those are smoothed
    away first (``meshReport['shortFeatures']`` counts them,
    ``meshReport['shortFeatureMove']`` is the largest distance an input
    vertex moved).  With the default ``surfaceSize`` and ``facetDistance`` the surface is
    refined until the mesh keeps at least 99 % of the volume the surface
    encloses; with either given, a mesh keeping less is returned with a
    RuntimeWarning.  The returned Mesh carries ``surfaceVolume`` (enclosed by
    the surface), ``volumeKept`` (mesh volume / surfaceVolume) and
    ``meshReport`` (a dict: the surfaceSize and facetDistance of the last
    meshing, the number of meshings, the thinnest part found, the short
    features smoothed).  Equal inputs
    and ``seed`` give identical meshes.  doc/meshes.md gives the guarantees
    and their cost."""
    if not getattr(_core, "haveCgal", False):
        raise RuntimeError("qdem was built without CGAL: install libcgal-dev and rebuild (make build)")
    if isinstance(surface, (str, os.PathLike)):
        verts, tris = loadSurface(surface, scale)
    else:
        verts, tris = surface
        verts = np.asarray(verts, dtype=float) * scale
    nodes, tets, report = _core.meshClosedSurface(np.ascontiguousarray(verts, dtype=float),
                                                  np.ascontiguousarray(tris, dtype=np.int32),
                                                  float(cellSize), float(facetDistance), int(seed),
                                                  float(surfaceSize) if surfaceSize else -1.0)
    try:
        mesh = Mesh(nodes, tets)
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
                             "most about the thickness, here <= %.3g, or another seed"
                             % (e, thickness, "surfaceSize" if surfaceSize else "cellSize", skin,
                                thickness)) from None
        raise
    mesh.surfaceVolume = report["surfaceVolume"]
    mesh.volumeKept = report["meshVolume"] / report["surfaceVolume"]
    mesh.meshReport = report
    if mesh.volumeKept < 0.99:
        warnings.warn("meshSurface: the mesh keeps %.1f %% of the volume the surface encloses (its mass is %.1f %% "
                      "low): %s; leave surfaceSize and facetDistance at their defaults to refine the surface until "
                      "99 %% is kept, or use smaller ones"
                      % (100 * mesh.volumeKept, 100 * (1 - mesh.volumeKept),
                         ", ".join("%s=%.3g" % (k, report[k]) for k in ("surfaceSize", "facetDistance"))),
                      RuntimeWarning, stacklevel=2)
    return mesh


def asMesh(obj):
    """Mesh from a Mesh, a (nodes, tets) tuple or a mesh file path."""
    if isinstance(obj, Mesh):
        return obj
    if isinstance(obj, (str, os.PathLike)):
        return loadMesh(obj)
    if isinstance(obj, tuple) and len(obj) == 2:
        return Mesh(*obj)
    raise ValueError("expected a qdem.Mesh, a (nodes, tets) tuple or a mesh file path, got %r" % type(obj))
