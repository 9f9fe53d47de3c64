"""Mesh loading defects (tester's probe C): file node numbering kept through
loadMesh and addPiece, internal cracks (coincident nodes inside one part),
quad and polygon faces of a surface file, coordinates far from the origin."""
import re

import numpy as np
import pytest

import qdem
from conftest import rubber


def _writeMsh(path, points, cells):
    import meshio
    meshio.write(str(path), meshio.Mesh(points, cells), file_format="gmsh22", binary=False)
    return str(path)


# --- 1. originalNodeIds are the file's point indices ------------------------------

def _fileWithGeometryPoints(tmp_path):
    """A box whose file also holds two points no tetrahedron uses: one first
    (gmsh writes geometry points first) and one among the mesh's nodes."""
    m = qdem.boxMesh((0.2, 0.2, 0.2), (2, 2, 2))
    k = 10
    pts = np.vstack([[[5.0, 5.0, 5.0]], m.nodes[:k], [[7.0, 7.0, 7.0]], m.nodes[k:]])
    tets = m.tets + 1
    tets[tets > k] += 1
    path = _writeMsh(tmp_path / "geompoints.msh", pts, [("vertex", np.array([[0], [k + 1]])), ("tetra", tets)])
    return path, pts


@pytest.mark.parametrize("source", ["mesh", "path", "reorder=False"])
def test_original_node_ids_are_the_file_point_indices(tmp_path, source):
    """Before: the unused points were dropped and originalNodeIds counted the
    remaining nodes, so file point i was mapped to the wrong solver node."""
    path, pts = _fileWithGeometryPoints(tmp_path)
    mesh = qdem.loadMesh(path)
    assert mesh.nNodes == len(pts) - 2
    assert np.array_equal(mesh.nodes, pts[mesh.nodeIds])
    w = qdem.World()
    p = w.addPiece(path if source == "path" else mesh, rubber(), reorder=source != "reorder=False")
    ids = np.asarray(p.originalNodeIds)
    assert np.array_equal(p.refPos, pts[ids])                 # solver node i is file point ids[i]
    assert set(ids) == set(range(len(pts))) - {0, 11}
    bottom = np.flatnonzero(np.isclose(pts[:, 2], -0.1))      # picked in the file, as a user would
    assert np.allclose(p.pos[np.isin(ids, bottom), 2], -0.1) and np.isin(ids, bottom).sum() == 9


def test_file_point_indices_survive_split_and_scale(tmp_path):
    m = qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2))
    pts = np.vstack([[[9.0, 9.0, 9.0]], m.nodes, m.nodes + (0.3, 0, 0)])
    path = _writeMsh(tmp_path / "two.msh", pts, [("tetra", np.vstack([m.tets, m.tets + m.nNodes]) + 1)])
    loaded = qdem.loadMesh(path)
    for part in qdem.splitMesh(loaded) + [loaded.scaled(2.0)]:
        scale = 2.0 if part.nNodes == loaded.nNodes else 1.0
        assert np.array_equal(part.nodes, scale * pts[part.nodeIds])
    w = qdem.World()
    for part in qdem.splitMesh(loaded):
        p = w.addPiece(part, rubber())
        assert np.array_equal(p.refPos, pts[p.originalNodeIds])
    made = qdem.World().addPiece(m, rubber())                   # a mesh not from a file: its own indices
    assert np.array_equal(made.refPos, m.nodes[made.originalNodeIds])


# --- 2. coincident nodes inside one part: an internal crack ---------------------------

def _crackedBar():
    """The upper half of the plane x = 0 of a bar duplicated for the tets on
    its +x side: one connected part with an internal crack."""
    m = qdem.boxMesh((0.2, 0.1, 0.1), (4, 2, 2))
    nodes, tets = m.nodes.copy(), m.tets.copy()
    crack = np.flatnonzero(np.isclose(nodes[:, 0], 0.0) & (nodes[:, 2] > 1e-12))
    twin = {int(n): len(nodes) + k for k, n in enumerate(crack)}
    nodes = np.vstack([nodes, nodes[crack]])
    right = nodes[tets].mean(axis=1)[:, 0] > 0
    tets[right] = np.vectorize(lambda n: twin.get(int(n), int(n)))(tets[right])
    return nodes, tets


def test_a_mesh_with_an_internal_crack_is_refused_naming_the_nodes_and_the_fix(tmp_path):
    """Before: accepted as one piece whose crack faces pass through each other."""
    nodes, tets = _crackedBar()
    msg = (r"3 pairs of distinct nodes at identical coordinates in one connected part \(nodes 32 and 45 at "
           r"\(0, -0.05, 0.05\), .*internal crack.*Merge the duplicate nodes \(gmsh: 'Coherence Mesh;'")
    with pytest.raises(ValueError, match=msg):
        qdem.Mesh(nodes, tets)
    with pytest.raises(ValueError, match="at identical coordinates"):
        qdem.World().addPiece((nodes, tets), rubber())
    pts = np.vstack([[[1.0, 1.0, 1.0]], nodes])                 # from a file: named with the file's indices too
    path = _writeMsh(tmp_path / "crack.msh", pts, [("tetra", tets + 1)])
    with pytest.raises(ValueError, match=r"nodes 32 \(point 33 of the file\) and 45 \(point 46 of the file\)"):
        qdem.loadMesh(path)
    u, inv = np.unique(nodes, axis=0, return_inverse=True)      # the recipe the message gives
    merged = qdem.Mesh(u, inv.ravel()[tets])
    assert merged.nNodes == len(nodes) - 3
    assert merged.volumes().sum() == pytest.approx(0.2 * 0.1 * 0.1, rel=1e-12)


def test_coincident_nodes_of_separate_parts_and_unused_ones_are_not_called_a_crack():
    """Two blocks touching in one file (a bar cut right through) are two parts:
    splitMesh makes them pieces.  An unused duplicate is refused by addPiece as
    unused, not as a crack."""
    m = qdem.boxMesh((0.2, 0.1, 0.1), (4, 2, 2))
    nodes, tets = m.nodes.copy(), m.tets.copy()
    cut = np.flatnonzero(np.isclose(nodes[:, 0], 0.0))
    twin = {int(n): len(nodes) + k for k, n in enumerate(cut)}
    nodes = np.vstack([nodes, nodes[cut]])
    right = nodes[tets].mean(axis=1)[:, 0] > 0
    tets[right] = np.vectorize(lambda n: twin.get(int(n), int(n)))(tets[right])
    assert [p.nTets for p in qdem.splitMesh(qdem.Mesh(nodes, tets))] == [48, 48]
    spare = qdem.Mesh(np.vstack([m.nodes, m.nodes[:1]]), m.tets)
    with pytest.raises(ValueError, match="belongs to no tetrahedron"):
        qdem.World().addPiece(spare, rubber())


# --- 3. quad and polygon faces of a surface file ----------------------------------------

_CUBE = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float) - 0.5
_QUADS = np.array([(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)])


def _obj(path, verts, faces):
    with open(path, "w") as f:
        f.writelines("v %r %r %r\n" % tuple(v) for v in verts)
        f.writelines("f %s\n" % " ".join("%d" % (i + 1) for i in face) for face in faces)
    return str(path)


def _prism(outline, height=1.0):
    """A prism over a counter-clockwise outline: its two caps as single faces."""
    n = len(outline)
    v = np.array([(x, y, z) for z in (0.0, height) for x, y in outline])
    caps = [list(range(n))[::-1], list(range(n, 2 * n))]
    sides = [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return v, caps + sides


def _area(outline):
    x, y = np.asarray(outline, dtype=float).T
    return 0.5 * (x @ np.roll(y, -1) - y @ np.roll(x, -1))


@pytest.mark.skipif(not qdem._core.haveCgal, reason="built without CGAL")
def test_surfaces_of_quads_and_convex_polygons_are_meshed(tmp_path):
    """Before: quads were dropped ('contains no triangles', or 'not closed' with
    quads and triangles mixed)."""
    tris = [t for a, b, c, d in _QUADS[4:] for t in ((a, b, c), (a, c, d))]
    pentagon = [(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 6)[:-1]]
    dart = [(0, 0), (1, 0.3), (2, 0), (1, 1)]            # concave at corner 1: split along the other diagonal
    cases = [(_CUBE, _QUADS, 1.0), (_CUBE, list(_QUADS[:4]) + tris, 1.0),
             _prism(pentagon) + (_area(pentagon),), _prism(dart) + (_area(dart),)]
    for k, (v, faces, volume) in enumerate(cases):
        v, f = qdem.loadSurface(_obj(tmp_path / ("s%d.obj" % k), v, faces))
        assert len(f) == sum(len(face) - 2 for face in faces)
        mesh = qdem.meshSurface((v, f), 0.25)
        assert (mesh.volumes() > 0).all()
        assert mesh.volumes().sum() == pytest.approx(volume, rel=0.02)


def _off(path, verts, faces, colour=""):
    with open(path, "w") as f:
        f.write("OFF\n# a comment\n%d %d 0\n" % (len(verts), len(faces)))
        f.writelines("%r %r %r\n" % tuple(v) for v in verts)
        f.writelines("%d %s%s\n" % (len(face), " ".join("%d" % i for i in face), colour) for face in faces)
    return str(path)


@pytest.mark.skipif(not qdem._core.haveCgal, reason="built without CGAL")
def test_an_off_surface_of_quads_and_polygons_is_meshed(tmp_path):
    """meshio reads only triangles from OFF ("Can only read triangular
    faces"): a cube of quads written as OFF was refused, as OBJ it loaded (a
    tester).  OFF is read by qdem itself, colours after a face ignored."""
    pentagon = [(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 6)[:-1]]
    for k, (v, faces, volume, colour) in enumerate([(_CUBE, _QUADS, 1.0, ""), (_CUBE, _QUADS, 1.0, " 255 0 0"),
                                                    _prism(pentagon) + (_area(pentagon), " 0.5 0.5 0.5 1")]):
        path = _off(tmp_path / ("s%d.off" % k), v, faces, colour)
        vv, f = qdem.loadSurface(path)
        assert len(f) == sum(len(face) - 2 for face in faces)
        assert qdem.meshSurface(path, 0.25).volumes().sum() == pytest.approx(volume, rel=0.02)
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n8 6 0\n0 0 0\n")
    with pytest.raises(ValueError, match="cannot read .*bad.off as OFF"):
        qdem.loadSurface(str(bad))


def test_a_non_convex_polygon_face_is_refused_naming_it(tmp_path):
    ell = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    v, faces = _prism(ell)
    with pytest.raises(ValueError, match=r"a face of 6 corners \(vertices 5 4 3 2 1 0, counted from 0\) is not "
                                         r"convex.*Triangulate"):
        qdem.loadSurface(_obj(tmp_path / "ell.obj", v, faces))


# --- 4. coordinates far from the origin ---------------------------------------------

@pytest.mark.parametrize("offset, size, cells", [(1e10, 0.3, 3), (1e14, 0.3, 3), (-1e10, 1.0, 1)])
def test_a_mesh_far_from_the_origin_is_refused_naming_the_offset_and_the_fix(tmp_path, offset, size, cells):
    """Before: a 0.3 m box at 1e10 m loaded with a 1.4e-5 volume error, at
    1e14 m with 8 %, silently."""
    import meshio
    m = qdem.boxMesh(size, cells)
    path = str(tmp_path / "far.vtu")
    meshio.write(path, meshio.Mesh(m.nodes + offset, [("tetra", m.tets)]))
    with pytest.raises(ValueError, match=r"coordinates reach %s m .*mesh centre \(%s, .*Translate the mesh near "
                                         r"the origin.*addPiece\(mesh, material, pos=centre\)"
                                         % (re.escape("%.3g" % abs(offset)), re.escape("%.10g" % offset))):
        qdem.loadMesh(path)


@pytest.mark.parametrize("offset, size, cells", [(1e6, 1.0, 1), (1e8, 2.0, 2), (-1e7, 0.04, 4)])
def test_utm_like_offsets_with_ordinary_elements_load(tmp_path, offset, size, cells):
    import meshio
    m = qdem.boxMesh(size, cells)
    path = str(tmp_path / "utm.vtu")
    meshio.write(path, meshio.Mesh(m.nodes + (offset, -offset, 0.5 * offset), [("tetra", m.tets)]))
    mesh = qdem.loadMesh(path)
    assert mesh.volumes().sum() == pytest.approx(size ** 3, rel=1e-6)
