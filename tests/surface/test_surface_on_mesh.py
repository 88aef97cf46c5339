"""Surface results on the user's own mesh: curvature's coarse-mesh warning, values sampled
at the input mesh's vertices, and the labelled pictures."""

import warnings

import numpy as np
import pytest
import trimesh

from clpde.cli import main


def test_curvature_warns_on_a_mesh_too_coarse_for_its_averaging(tmp_path, capsys):
    path = tmp_path / "box.ply"
    trimesh.creation.box().export(path)  # 12 faces: every edge as long as the box
    assert main(["surface", "curvature", str(path), "-o", str(tmp_path / "box"),
                 "--resolution", "16", "--size", "32"]) == 0
    assert "warning: the mesh is too coarse for curvature: 12 faces" in capsys.readouterr().err


def test_curvature_on_a_fine_mesh_does_not_warn(tmp_path, capsys):
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(3).export(path)
    assert main(["surface", "curvature", str(path), "-o", str(tmp_path / "ball"),
                 "--resolution", "16", "--size", "32"]) == 0
    assert "too coarse" not in capsys.readouterr().err


def test_library_warning_for_a_coarse_mesh():
    from clpde.cli.surface import warn_if_too_coarse

    box = trimesh.creation.box()
    with pytest.warns(UserWarning, match="too coarse"):
        assert warn_if_too_coarse(box, float(np.median(box.edges_unique_length)))


def test_coarse_share_of_common_meshes():
    from clpde.cli.surface import warn_if_too_coarse

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for mesh in (trimesh.creation.icosphere(2), trimesh.creation.torus(1.0, 0.3),
                     trimesh.creation.box().subdivide_to_size(0.1)):
            sigma = float(np.median(mesh.edges_unique_length))
            assert not warn_if_too_coarse(mesh, sigma)
