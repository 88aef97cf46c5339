"""`clpde surface FLOW MESH -o OUTDIR` end to end on small grids."""

import imageio.v3 as iio
import numpy as np
import pytest
import trimesh

from clpde.cli import main


def test_surface_heat_on_a_generated_shape(tmp_path, capsys):
    out = tmp_path / "heat"
    assert (
        main(["surface", "heat", "sphere", "-o", str(out), "--resolution", "24", "--size", "64"])
        == 0
    )
    before, after = iio.imread(out / "before.png"), iio.imread(out / "after.png")
    assert before.shape == after.shape and after.shape[1] == 128
    assert after.shape[0] > 64  # the views, then the colour bar
    # heat smooths the checkerboard: fewer saturated colours after
    assert np.std(after.astype(float)) < np.std(before.astype(float))
    mesh = trimesh.load(out / "result.ply", force="mesh")
    assert len(mesh.faces) > 100 and mesh.visual.vertex_colors.shape[0] == len(mesh.vertices)
    assert "wrote 4 files" in capsys.readouterr().err


def test_surface_on_a_mesh_file_and_errors(tmp_path, capsys):
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(3, radius=2.0).export(path)
    out = tmp_path / "curv"
    assert (
        main(
            [
                "surface",
                "curvature",
                str(path),
                "-o",
                str(out),
                "--resolution",
                "24",
                "--size",
                "48",
            ]
        )
        == 0
    )
    assert (out / "result.glb").stat().st_size > 0
    assert (
        main(["surface", "heat", str(tmp_path / "missing.obj"), "-o", str(out), "--overwrite"]) == 2
    )
    assert "neither a mesh file" in capsys.readouterr().err
    assert (
        main(["surface", "flowvis", "sphere", "-o", str(out), "--direction", "none", "--overwrite"])
        == 2
    )


def test_surface_chroma_denoises_a_meshs_own_colours(tmp_path, capsys):
    ball = trimesh.creation.icosphere(4, radius=2.0)

    def pattern(v):
        d = v / np.linalg.norm(v, axis=1, keepdims=True)
        return np.stack(
            [0.5 + 0.35 * np.tanh(4 * d[:, 0]), 0.5 + 0.3 * d[:, 1], 0.45 + 0 * d[:, 2]], 1
        )

    noisy = np.clip(
        pattern(ball.vertices)
        + 0.12 * np.random.default_rng(2).standard_normal((len(ball.vertices), 3)),
        0,
        1,
    )
    ball.visual.vertex_colors = np.concatenate(
        [np.rint(255 * noisy), np.full((len(noisy), 1), 255)], axis=1
    ).astype(np.uint8)
    path = tmp_path / "scan.ply"
    ball.export(path)
    data = path.read_bytes()
    out = tmp_path / "chroma"
    assert (
        main(["surface", "chroma", str(path), "-o", str(out), "--resolution", "32", "--size", "48"])
        == 0
    )
    assert "the mesh's colours" in capsys.readouterr().err
    assert path.read_bytes() == data  # the input is never modified
    result = trimesh.load(out / "result.ply", force="mesh")
    colours = result.visual.vertex_colors[:, :3] / 255.0
    error_after = np.sqrt(((colours - pattern(result.vertices)) ** 2).mean())
    error_before = np.sqrt(((noisy - pattern(ball.vertices)) ** 2).mean())
    assert error_after < 0.35 * error_before, (error_before, error_after)  # 0.117 -> 0.021
    # a mesh without colours cannot give them
    plain = tmp_path / "plain.ply"
    trimesh.creation.icosphere(2, radius=2.0).export(plain)
    assert (
        main(
            [
                "surface",
                "heat",
                str(plain),
                "-o",
                str(out),
                "--resolution",
                "24",
                "--data",
                "mesh",
                "--overwrite",
            ]
        )
        == 2
    )
    assert "no vertex colours" in capsys.readouterr().err


def test_warnings_are_one_line_for_the_user(tmp_path, capsys):
    ball = trimesh.creation.icosphere(2, radius=2.0)
    ball.update_faces(np.arange(len(ball.faces)) != 3)  # not watertight: a warning
    path = tmp_path / "open.ply"
    ball.export(path)
    assert (
        main(
            [
                "surface",
                "heat",
                str(path),
                "-o",
                str(tmp_path / "out"),
                "--resolution",
                "24",
                "--size",
                "32",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "clpde: warning: the mesh is not watertight" in err
    assert ".py:" not in err  # no source locations


def _bar(picture, size):
    """The colour bar's rows below the views."""
    return picture[size:]


def test_every_scalar_render_has_a_colour_bar(tmp_path):
    from clpde.surface import ImplicitSurface
    from clpde.surface.render import _RAMP

    out = tmp_path / "heat"
    assert (
        main(["surface", "heat", "sphere", "-o", str(out), "--resolution", "24", "--size", "64"])
        == 0
    )
    for name in ("before.png", "after.png"):
        bar = _bar(iio.imread(out / name), 64).reshape(-1, 3).astype(float) / 255
        # both ends of the colour ramp are drawn, and black label text
        for end in (_RAMP[0], _RAMP[-1]):
            assert np.abs(bar - end).max(axis=1).min() < 0.03
        assert (bar.sum(axis=1) < 0.3).any()
    surf = ImplicitSurface.sphere(1.0, 0.1)
    x, _, _ = surf.coordinates()
    picture = surf.render(np.broadcast_to(x, surf.shape), size=96)
    assert picture.shape[0] > 96 and picture.shape[1] == 96
    assert surf.render(np.broadcast_to(x, surf.shape), size=96, colour_bar=False).shape == (
        96,
        96,
        3,
    )
    assert surf.render(None, size=96).shape == (96, 96, 3)  # nothing to scale


def test_curvature_of_a_mesh_shows_its_shape_not_its_triangles(tmp_path):
    from clpde.surface.runs import load_surface, run_flow

    path = tmp_path / "ico.ply"
    trimesh.creation.icosphere(3, radius=2.0).export(path)
    run = run_flow(load_surface(str(path), 40), "curvature")
    values = run.surface.to_mesh(run.after).vertex_attributes["u"]
    # a sphere of radius 2: mean curvature 1/2 everywhere (at the grid's scale the
    # triangles' edges and vertices gave 0 to 1.6, a spread of 70% of the mean)
    assert np.median(values) == pytest.approx(0.5, rel=0.03)
    assert values.std() < 0.03 * np.median(values)
    out = tmp_path / "curv"
    assert (
        main(
            [
                "surface",
                "curvature",
                str(path),
                "-o",
                str(out),
                "--resolution",
                "24",
                "--size",
                "48",
            ]
        )
        == 0
    )
    before, after = iio.imread(out / "before.png"), iio.imread(out / "after.png")
    assert before.shape != after.shape or not np.array_equal(before, after)
    from clpde.surface.render import title_height

    top = title_height(after.shape[1])  # the title strip above the views
    views = after[top : top + 48].reshape(-1, 3).astype(int)
    surface = views[(views != 255).any(axis=1)]
    hue = surface / np.maximum(surface.sum(axis=1, keepdims=True), 1)
    assert hue.std(axis=0).max() < 0.02  # one flat colour (shaded), no dots at the vertices
    grey = before[top : top + 48].reshape(-1, 3).astype(int)
    assert (grey.max(axis=1) - grey.min(axis=1)).max() <= 2  # the bare shape, in grey


def test_tv_default_flattens_the_squares_and_keeps_their_edges():
    """TV flow on a surface looked like heat (its default time rounded the
    squares into blobs). Against heat that leaves as much noise, it keeps the edges sharp."""
    from scipy import ndimage

    from clpde.surface import checker
    from clpde.surface.runs import load_surface, run_flow

    surf = load_surface("torus", 48)
    h = surf.spacing
    run = run_flow(surf, "tv", sigma=0.15)
    clean = checker(surf)
    near = np.abs(surf.psi) < 0.5 * h
    interior = near & (ndimage.maximum_filter(clean, 7) == ndimage.minimum_filter(clean, 7))
    edge = near & ~interior

    def noise_and_blur(u):
        return np.std((u - clean)[interior]), np.mean((u[edge] > 0.3) & (u[edge] < 0.7))

    tv, heat = noise_and_blur(run.after), noise_and_blur(surf.heat(run.before, t=h**2))
    assert tv[0] < 0.045 and tv[0] < 1.1 * heat[0]  # measured 0.032 and 0.037
    assert tv[1] < 0.5 * heat[1]  # measured 0.12 and 0.38


def test_storage_bricks_gives_the_lists_pictures(tmp_path):
    """--storage bricks: the same run in the band's bricks, the same result."""
    for storage in ("lists", "bricks"):
        assert (
            main(
                [
                    "surface",
                    "denoise",
                    "sphere",
                    "-o",
                    str(tmp_path / storage),
                    "--resolution",
                    "24",
                    "--size",
                    "48",
                    "--storage",
                    storage,
                ]
            )
            == 0
        )
    lists = trimesh.load(tmp_path / "lists" / "result.ply", force="mesh")
    bricks = trimesh.load(tmp_path / "bricks" / "result.ply", force="mesh")
    np.testing.assert_allclose(bricks.visual.vertex_colors, lists.visual.vertex_colors, atol=1)
    assert main(["surface", "heat", "sphere", "-o", str(tmp_path / "x"), "--storage", "dense"]) == 2
