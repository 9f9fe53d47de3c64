"""Meshes from files (meshio) and from closed surfaces (CGAL), VTU output."""
import os

import numpy as np
import pytest

import qdem


@pytest.mark.parametrize("ext", ["vtu", "msh", "mesh"])
def test_load_mesh_roundtrip(tmp_path, ext):
    import meshio
    m = qdem.boxMesh((0.3, 0.2, 0.1), (3, 2, 1), tetsPerCell=6)
    path = str(tmp_path / ("box." + ext))
    kw = {"file_format": "gmsh22"} if ext == "msh" else {}
    meshio.write(path, meshio.Mesh(m.nodes, [("tetra", m.tets)]), **kw)
    back = qdem.loadMesh(path)
    assert back.nTets == m.nTets
    assert back.volumes().sum() == pytest.approx(0.3 * 0.2 * 0.1, rel=1e-12)


def test_inverted_file_is_fixed_only_on_request(tmp_path):
    import meshio
    m = qdem.boxMesh((1, 1, 1), (2, 2, 2))
    path = str(tmp_path / "flipped.vtu")
    meshio.write(path, meshio.Mesh(m.nodes, [("tetra", m.tets[:, [0, 2, 1, 3]])]))
    with pytest.raises(ValueError, match="inverted"):
        qdem.loadMesh(path)
    assert (qdem.loadMesh(path, fixOrientation=True).volumes() > 0).all()


def _cubeSurface():
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    q = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = np.array([t for a, b, c, d in q for t in ((a, b, c), (a, c, d))], dtype=np.int32)
    return v, tris


@pytest.mark.skipif(not qdem._core.haveCgal, reason="built without CGAL")
def test_mesh_closed_surface_with_cgal(tmp_path):
    import meshio
    v, tris = _cubeSurface()
    path = str(tmp_path / "cube.off")
    meshio.write(path, meshio.Mesh(v, [("triangle", tris)]))
    coarse = qdem.meshSurface(path, cellSize=0.25)
    fine = qdem.meshSurface((v, tris), cellSize=0.12)
    assert fine.nTets > coarse.nTets > 10
    for m in (coarse, fine):
        assert (m.volumes() > 0).all()
        assert m.volumes().sum() == pytest.approx(1.0, rel=0.02)


@pytest.mark.skipif(not qdem._core.haveCgal, reason="built without CGAL")
def test_open_surface_is_rejected():
    v, tris = _cubeSurface()
    with pytest.raises(ValueError, match="closed|manifold"):
        qdem.meshSurface((v, tris[:-1]), cellSize=0.25)
