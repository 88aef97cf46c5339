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
    assert (
        main(
            [
                "surface",
                "curvature",
                str(path),
                "-o",
                str(tmp_path / "box"),
                "--resolution",
                "16",
                "--size",
                "32",
            ]
        )
        == 0
    )
    assert "warning: the mesh is too coarse for curvature: 12 faces" in capsys.readouterr().err


def test_curvature_on_a_fine_mesh_does_not_warn(tmp_path, capsys):
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(3).export(path)
    assert (
        main(
            [
                "surface",
                "curvature",
                str(path),
                "-o",
                str(tmp_path / "ball"),
                "--resolution",
                "16",
                "--size",
                "32",
            ]
        )
        == 0
    )
    assert "too coarse" not in capsys.readouterr().err


def test_library_warning_for_a_coarse_mesh():
    from clpde.surface.runs import warn_if_too_coarse

    box = trimesh.creation.box()
    with pytest.warns(UserWarning, match="too coarse"):
        assert warn_if_too_coarse(box, float(np.median(box.edges_unique_length)))


def test_coarse_share_of_common_meshes():
    from clpde.surface.runs import warn_if_too_coarse

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for mesh in (
            trimesh.creation.icosphere(2),
            trimesh.creation.torus(1.0, 0.3),
            trimesh.creation.box().subdivide_to_size(0.1),
        ):
            sigma = float(np.median(mesh.edges_unique_length))
            assert not warn_if_too_coarse(mesh, sigma)


def test_values_sampled_on_a_sphere_mesh_match_the_function():
    """u = z / |x| is constant along the sphere's normals, so the band holds it as its own
    extension; read at the input mesh's vertices (on the unit sphere) it is their z."""
    from clpde.surface import ImplicitSurface
    from clpde.surface.render import on_mesh

    ball = trimesh.creation.icosphere(3)
    surf = ImplicitSurface.from_mesh(ball, resolution=24)
    u = surf.field(lambda x, y, z: z / np.sqrt(x * x + y * y + z * z + 1e-30))
    for interpolation, tol in (("tricubic", 2e-3), ("trilinear", 2e-2)):
        result = on_mesh(surf, u, interpolation=interpolation)
        assert len(result.vertices) == len(ball.vertices)
        np.testing.assert_array_equal(result.faces, ball.faces)
        got = result.vertex_attributes["u"]
        assert np.abs(got - ball.vertices[:, 2]).max() < tol
    assert result.visual.vertex_colors.shape == (len(ball.vertices), 4)
    rgb = on_mesh(surf, np.stack([u, -u, u]))
    np.testing.assert_allclose(rgb.vertex_attributes["u1"], -rgb.vertex_attributes["u0"])


def test_on_mesh_needs_a_mesh():
    from clpde import InputError
    from clpde.surface import ImplicitSurface
    from clpde.surface.render import on_mesh

    surf = ImplicitSurface.sphere(1.0, spacing=0.2)
    with pytest.raises(InputError, match="not made from a mesh"):
        on_mesh(surf, surf.field(lambda x, y, z: x))


def test_cli_writes_results_on_the_input_mesh_by_default(tmp_path):
    import imageio.v3 as iio

    torus = trimesh.creation.torus(1.0, 0.35, major_sections=24, minor_sections=12)
    path = tmp_path / "torus.ply"
    torus.export(path)
    out = tmp_path / "on"
    assert (
        main(["surface", "heat", str(path), "-o", str(out), "--resolution", "24", "--size", "48"])
        == 0
    )
    result = trimesh.load(out / "result.ply", process=False)
    assert len(result.vertices) == len(torus.vertices)
    ply = (out / "result.ply").read_bytes()
    assert b"property double u\n" in ply and b"property uchar red" in ply
    # the pictures carry a title strip above the two views and a colour bar below
    after = iio.imread(out / "after.png")
    assert after.shape[0] > 48 + 20
    remesh = tmp_path / "remesh"
    assert (
        main(
            [
                "surface",
                "heat",
                str(path),
                "-o",
                str(remesh),
                "--resolution",
                "24",
                "--size",
                "48",
                "--on",
                "remesh",
            ]
        )
        == 0
    )
    assert len(trimesh.load(remesh / "result.ply", process=False).vertices) != len(torus.vertices)
    assert main(["surface", "heat", "sphere", "-o", str(tmp_path / "s"), "--on", "input"]) == 2
