"""Bad input gets a clear error naming the problem, never a crash or a silent NaN."""
import numpy as np
import pytest

import qdem


def _tet():
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return nodes, np.array([[0, 1, 2, 3]])


def test_inverted_tet():
    nodes, tets = _tet()
    with pytest.raises(ValueError, match="tetrahedron 0 is inverted"):
        qdem.Mesh(nodes, tets[:, [0, 2, 1, 3]])


def test_zero_volume_tet():
    nodes, tets = _tet()
    nodes[3] = (0.5, 0.5, 0.0)
    with pytest.raises(ValueError, match="zero volume"):
        qdem.Mesh(nodes, tets)
    with pytest.raises(ValueError, match="repeats node"):
        qdem.Mesh(nodes, [[0, 1, 1, 3]])


def test_nan_coordinate():
    nodes, tets = _tet()
    nodes[2, 1] = np.nan
    with pytest.raises(ValueError, match="node 2 has a NaN"):
        qdem.Mesh(nodes, tets)


def test_index_out_of_range_and_bad_shapes():
    nodes, tets = _tet()
    with pytest.raises(ValueError, match="refers to node 7"):
        qdem.Mesh(nodes, [[0, 1, 2, 7]])
    with pytest.raises(ValueError, match="shape"):
        qdem.Mesh(nodes[:, :2], tets)
    with pytest.raises(ValueError, match="integer"):
        qdem.Mesh(nodes, tets.astype(float))


@pytest.mark.parametrize("kw, word", [({"young": 0}, "young"), ({"young": -1e6}, "young"),
                                      ({"poisson": 0.5}, "poisson"), ({"poisson": -1.0}, "poisson"),
                                      ({"density": 0}, "density"), ({"viscosity": -1}, "viscosity"),
                                      ({"young": float("nan")}, "young"), ({"restitution": 0}, "restitution")])
def test_bad_material_parameters(kw, word):
    with pytest.raises(ValueError, match=word):
        qdem.QdemMat(**kw)


def test_unknown_keywords():
    with pytest.raises(TypeError, match="unknown keyword 'youngs'"):
        qdem.QdemMat(youngs=1e6)
    with pytest.raises(TypeError, match="unknown keyword 'gravity'"):
        qdem.QdemEngine(gravity=(0, 0, -9.81))


def test_bad_piece_arguments():
    w = qdem.World()
    with pytest.raises(ValueError, match="material"):
        w.addPiece(qdem.boxMesh(), material="steel")
    with pytest.raises(ValueError, match="rotation"):
        w.addPiece(qdem.boxMesh(), ori=np.ones((3, 3)))
    with pytest.raises(ValueError, match="no such file"):
        w.addPiece("does/not/exist.msh")
    assert w.core.nPieces == 0          # nothing half-added


def test_broken_mesh_files(tmp_path):
    bad = tmp_path / "broken.msh"
    bad.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\ngarbage\n")
    with pytest.raises(ValueError, match="cannot read"):
        qdem.loadMesh(str(bad))
    tri = tmp_path / "flat.vtu"
    import meshio
    meshio.write(str(tri), meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(ValueError, match="no tetrahedra"):
        qdem.loadMesh(str(tri))


def test_nan_state_is_reported_not_propagated():
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat(viscosity=0))
    p.vel[3, 0] = np.nan
    w.core.step(1e-7, 3)
    with pytest.raises(qdem.StabilityError, match="not finite at node"):
        w.core.checkFinite()


def test_mesh_with_unused_node_is_rejected():
    nodes, tets = _tet()
    nodes = np.vstack([nodes, [5, 5, 5]])
    w = qdem.World()
    with pytest.raises(ValueError, match="belongs to no tetrahedron"):
        w.addPiece((nodes, tets), reorder=False)
