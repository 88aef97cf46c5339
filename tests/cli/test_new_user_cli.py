"""What a new user hit, through the command line: each case as the user typed it,
with a one-line `clpde: error: ...` (or warning) that gives command-line advice."""

import itertools
import os
import sys

import numpy as np
import pytest

import clpde
from clpde.cli import main
from clpde.io.images import read_image, write_image


def _one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("clpde: error: "), err
    return err[0]


@pytest.fixture
def noisy_png(tmp_path):
    rng = np.random.default_rng(5)
    xx = np.mgrid[:40, :48][1]
    image = np.clip(60 + 120 * (xx > 23) + rng.normal(0, 15, xx.shape), 0, 255).astype(np.uint8)
    path = tmp_path / "noisy.png"
    write_image(path, image)
    return path, image


# ---- 1. the default denoise ---------------------------------------------------------------
def test_default_denoise_works_without_pywavelets(noisy_png, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "pywt", None)  # a fresh install has no PyWavelets
    path, image = noisy_png
    assert main(["denoise", str(path), str(tmp_path / "clean.png")]) == 0
    result = read_image(tmp_path / "clean.png")
    np.testing.assert_array_equal(result, clpde.denoise_tv(image))
    # sigma was estimated near the 15 grey levels added: the residual reaches it
    residual = float(capsys.readouterr().err.split("residual std ")[1].split()[0].rstrip(","))
    assert residual == pytest.approx(15, rel=0.2)


# ---- 2 and 7. one rule for output folders -------------------------------------------------
def test_regions_rerun_holds_only_its_own_files(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["regions", "merge", "-o", str(out), "--spacing", "0.1", "--size", "32"]
    assert main([*args, "--saves", "2"]) == 0
    capsys.readouterr()
    assert main([*args, "--saves", "1"]) == 2
    assert "is not empty (4 entries); choose a new folder, or give --overwrite" in _one_error_line(
        capsys
    )
    assert main([*args, "--saves", "1", "--overwrite"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "regions.png",
        "regions_0.ply",
        "regions_1.ply",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging or old folder left


@pytest.mark.parametrize(
    "command",
    [
        ["surface", "heat", "sphere"],
        ["regions", "merge"],
        ["inpaint", "--demo"],
        ["track", "FRAMES", "--init", "MASK"],
    ],
)
def test_every_folder_command_has_one_rule(tmp_path, capsys, command):
    """Refused before any work: a non-empty folder without --overwrite, a folder with files
    clpde does not write even with it, and a missing parent (create it first)."""
    frames = tmp_path / "frames"
    frames.mkdir()
    write_image(frames / "f1.png", np.zeros((8, 8), np.uint8))
    write_image(tmp_path / "mask.png", np.zeros((8, 8), np.uint8))
    command = [
        str(frames) if a == "FRAMES" else str(tmp_path / "mask.png") if a == "MASK" else a
        for a in command
    ]
    out = tmp_path / "out"
    folder = out / "inpaint_demo" if "--demo" in command else out  # the demo's own folder
    folder.mkdir(parents=True)
    (folder / "old.png").write_bytes(b"old")
    assert main([*command, "-o", str(out)]) == 2
    assert "give --overwrite" in _one_error_line(capsys)
    (folder / "notes.txt").write_text("mine")
    assert main([*command, "-o", str(out), "--overwrite"]) == 2
    assert "'notes.txt', which clpde does not write" in _one_error_line(capsys)
    assert main([*command, "-o", str(tmp_path / "no" / "such")]) == 2
    assert "does not exist; create it first" in _one_error_line(capsys)
    assert sorted(os.listdir(folder)) == ["notes.txt", "old.png"]
    assert not (tmp_path / "no").exists()


# ---- 3. lossy and grey masks ----------------------------------------------------------------
def test_inpaint_reads_a_jpeg_mask_at_half_range_and_warns(noisy_png, tmp_path, capsys):
    from PIL import Image

    path, image = noisy_png
    truth = np.zeros(image.shape, bool)
    truth[10:12, 5:40] = truth[25:27, 5:40] = True
    Image.fromarray(truth.astype(np.uint8) * 255).save(tmp_path / "mask.jpg", quality=75)
    assert (
        main(
            [
                "inpaint",
                str(path),
                str(tmp_path / "mask.jpg"),
                "-o",
                str(tmp_path / "o.png"),
                "--max-steps",
                "20",
                "--levels",
                "1",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "clpde: warning: the mask" in err and "lossy JPEG" in err and ".py:" not in err
    filled = int(err.split("inpaint: ")[1].split()[0])
    assert abs(filled - truth.sum()) <= 0.05 * truth.sum()


# ---- 4. a CLPDE_DEVICE that matches nothing -------------------------------------------------
def test_devices_says_when_clpde_device_matches_nothing(monkeypatch, capsys):
    monkeypatch.setenv("CLPDE_DEVICE", "bogus")
    assert main(["devices"]) == 2
    listed = capsys.readouterr()
    err = listed.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("clpde: error: CLPDE_DEVICE='bogus' matches none")
    assert "unset it" in err[0]
    heads = [line for line in listed.out.splitlines() if not line.startswith("      ")]
    assert len(heads) == len(clpde.devices())  # the list (each device's paths below it)
    assert not [line for line in listed.out.splitlines() if line.startswith("*")]
    monkeypatch.delenv("CLPDE_DEVICE")
    assert main(["devices"]) == 0


# ---- 6. messages in command-line terms ------------------------------------------------------
@pytest.fixture
def nan_tiff(tmp_path):
    x = np.mgrid[0:24, 0:30][1]
    image = (0.2 + 0.02 * x).astype(np.float32)
    holed = image.copy()
    holed[8:12, 10:16] = np.nan
    path = tmp_path / "holed.tif"
    write_image(path, holed)
    return path, image, np.isnan(holed)


def test_inpaint_fills_nan_pixels_with_mask_nan(nan_tiff, tmp_path, capsys):
    path, image, holes = nan_tiff
    assert (
        main(
            ["inpaint", str(path), "nan", "-o", str(tmp_path / "filled.tif"), "--max-steps", "200"]
        )
        == 0
    )
    filled = read_image(tmp_path / "filled.tif")
    assert filled.dtype == np.float32 and np.isfinite(filled).all()
    np.testing.assert_array_equal(filled[~holes], image[~holes])
    assert np.abs(filled[holes] - image[holes]).max() < 0.05  # a ramp continues
    assert f"inpaint: {holes.sum()} pixels" in capsys.readouterr().err


def test_nan_pixels_get_command_line_advice(nan_tiff, tmp_path, capsys):
    path, _, _ = nan_tiff
    write_image(tmp_path / "none.png", np.zeros((24, 30), np.uint8))
    assert (
        main(["inpaint", str(path), str(tmp_path / "none.png"), "-o", str(tmp_path / "o.tif")]) == 2
    )
    line = _one_error_line(capsys)
    assert "24 NaN pixels outside the mask" in line and "give 'nan' as MASK" in line
    assert "mask=None" not in line
    assert main(["diffuse", str(path), str(tmp_path / "o.tif")]) == 2
    line = _one_error_line(capsys)
    assert f"clpde inpaint {path} nan -o FILLED.tif" in line and "clpde.inpaint" not in line
    assert main(["inpaint", str(tmp_path / "none.png"), "nan", "-o", str(tmp_path / "o.png")]) == 2
    assert "has no NaN pixels to fill" in _one_error_line(capsys)
    assert sorted(os.listdir(tmp_path)) == ["holed.tif", "none.png"]


def test_sixteen_bit_colour_to_jpeg_suggests_what_works(tmp_path, capsys):
    write_image(tmp_path / "deep.tif", np.full((6, 7, 3), 40000, np.uint16))
    assert main(["diffuse", str(tmp_path / "deep.tif"), str(tmp_path / "o.jpg")]) == 2
    line = _one_error_line(capsys)
    assert "write a .png or .tif file instead" in line  # both keep 16-bit colour
    assert (
        main(["diffuse", str(tmp_path / "deep.tif"), str(tmp_path / "o.tif"), "--steps", "1"]) == 0
    )


def test_mesh_messages(tmp_path, capsys):
    import trimesh

    assert main(["regions", "nosuch", "-o", str(tmp_path / "r")]) == 2
    assert "'nosuch' is neither a mesh file nor one of the scenes split" in _one_error_line(capsys)
    sheet = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    sheet.export(tmp_path / "sheet.ply")
    for command in (["surface", "heat"], ["regions"]):
        assert (
            main(
                [
                    *command,
                    str(tmp_path / "sheet.ply"),
                    "-o",
                    str(tmp_path / "s"),
                    "--resolution",
                    "16",
                ]
            )
            == 2
        )
        err = capsys.readouterr().err
        assert "encloses no volume (an open sheet" in err and "zero level set" not in err
    trimesh.creation.box([2, 2, 0.12]).export(tmp_path / "plate.ply")
    assert (
        main(
            [
                "surface",
                "heat",
                str(tmp_path / "plate.ply"),
                "-o",
                str(tmp_path / "s"),
                "--resolution",
                "24",
            ]
        )
        == 2
    )
    assert "thinner than the grid's spacing" in _one_error_line(capsys)
    assert not (tmp_path / "s").exists()


def test_coarse_grid_warning_names_resolution(tmp_path, capsys):
    import trimesh

    trimesh.creation.box([2, 2, 0.12]).export(tmp_path / "plate.ply")
    assert (
        main(
            [
                "surface",
                "heat",
                str(tmp_path / "plate.ply"),
                "-o",
                str(tmp_path / "s"),
                "--resolution",
                "32",
                "--size",
                "32",
                "--t",
                "1e-5",
            ]
        )
        == 0
    )
    warning = [line for line in capsys.readouterr().err.splitlines() if "too coarse" in line]
    assert len(warning) == 1
    assert "give a larger --resolution (such as 64" in warning[0]
    assert "spacing (below" not in warning[0] and "0.00%" not in warning[0]


def test_negligible_coarse_grid_shares_are_not_shown():
    import warnings

    from clpde.cli._common import grid_advice

    text = (
        "the grid is too coarse for this shape's thinnest features: {}% of the band lies on "
        "a medial axis (|grad psi| < 0.5); use a finer spacing (below 0.0123) or a narrower "
        "band"
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with grid_advice(50):
            warnings.warn(text.format("0.00"), stacklevel=1)
            warnings.warn(text.format("2.50"), stacklevel=1)
            warnings.warn("something else", stacklevel=1)
    assert [str(w.message).split("; ")[-1] for w in caught] == [
        "give a larger --resolution (such as 100, which halves the spacing)",
        "something else",
    ]


# ---- 8. the inpainting GIF --------------------------------------------------------------------
def test_inpaint_gif_starts_from_the_damaged_image_and_counts_what_it_writes(tmp_path, capsys):
    import imageio.v3 as iio

    y, x = np.mgrid[0:40, 0:48]
    truth = np.where(x + 0.5 * y > 30, 200, 60).astype(np.uint8)
    mask = np.zeros(truth.shape, bool)
    mask[15:21, 10:40] = True
    damaged = truth.copy()
    damaged[mask] = 255
    write_image(tmp_path / "d.png", damaged)
    write_image(tmp_path / "m.png", mask.astype(np.uint8) * 255)
    # converging early, the last states repeat: the count must be what the file holds
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "d.png"),
                str(tmp_path / "m.png"),
                "-o",
                str(tmp_path / "o.png"),
                "--gif",
                str(tmp_path / "e.gif"),
                "--gif-every",
                "20",
                "--levels",
                "1",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    frames = iio.imread(tmp_path / "e.gif", index=None)
    frames = frames[..., 0] if frames.ndim == 4 else frames
    assert f"({len(frames)} frames: the damaged image" in err
    np.testing.assert_array_equal(frames[0], damaged)
    np.testing.assert_array_equal(frames[-1], read_image(tmp_path / "o.png"))
    assert all(not np.array_equal(a, b) for a, b in itertools.pairwise(frames))
    assert np.abs(frames[1][mask].astype(float) - damaged[mask]).mean() > 50  # filled


# ---- 10. the regions default on a convex mesh -----------------------------------------------
def test_regions_says_when_the_surface_barely_moves(tmp_path, capsys, monkeypatch):
    import trimesh

    ball = trimesh.creation.icosphere(3, radius=1.0)
    cap = ball.vertices[:, 2] > 0.5
    ball.visual.vertex_colors = np.where(
        cap[:, None], [[230, 200, 30, 255]], [[110, 120, 170, 255]]
    ).astype(np.uint8)
    ball.export(tmp_path / "painted.ply")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)  # as on a terminal
    assert (
        main(
            [
                "regions",
                str(tmp_path / "painted.ply"),
                "-o",
                str(tmp_path / "a"),
                "--resolution",
                "20",
                "--saves",
                "1",
                "--size",
                "16",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert err.startswith("regions: building a grid of 20 cells")  # before the silent part
    # the default flow morphs towards the sphere of the same volume, which a ball already is
    assert "within a cell of the sphere of its volume" in err and "--flow mean-curvature" in err
    trimesh.creation.box([2.0, 1.0, 1.0]).export(tmp_path / "box.ply")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)
    assert (
        main(
            [
                "regions",
                str(tmp_path / "box.ply"),
                "-o",
                str(tmp_path / "b"),
                "--flow",
                "morph-sphere",
                "--resolution",
                "20",
                "--saves",
                "1",
                "--size",
                "16",
                "--t",
                "1",
            ]
        )
        == 0
    )
    assert "hardly moved" not in capsys.readouterr().err


# ---- one mask rule for the API and the command line; anti-aliased masks -------------------
def _lettered(tmp_path):
    """A photo-like image and a mask of letters drawn with anti-aliasing (soft grey rims)."""
    from PIL import Image, ImageDraw, ImageFont

    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[:48, :96]
    image = np.clip(100 + 60 * np.sin(xx / 7) + rng.normal(0, 4, xx.shape), 0, 255)
    image = np.stack([image, image[::-1], 255 - image], axis=-1).astype(np.uint8)
    canvas = Image.new("L", (96, 48), 0)
    ImageDraw.Draw(canvas).text((6, 8), "clpde", fill=255, font=ImageFont.load_default(size=28))
    soft = np.asarray(canvas)
    write_image(tmp_path / "photo.png", image)
    return image, soft


def test_an_rgb_mask_gets_the_same_fill_from_the_api_and_the_command_line(tmp_path, capsys):
    image, soft = _lettered(tmp_path)
    drawn = soft > 127
    rgba = np.zeros((*drawn.shape, 4), np.uint8)
    rgba[..., 3] = 255  # opaque: alpha is ignored
    rgba[drawn, 0] = 230  # painted in red
    write_image(tmp_path / "mask.png", rgba)
    api = clpde.inpaint(image, rgba, channel_axis=-1)  # refused before: a (rows, cols, 4) mask
    np.testing.assert_array_equal(api, clpde.inpaint(image, drawn, channel_axis=-1))
    out = tmp_path / "out.png"
    assert (
        main(["inpaint", str(tmp_path / "photo.png"), str(tmp_path / "mask.png"), "-o", str(out)])
        == 0
    )
    np.testing.assert_array_equal(read_image(out), api)


def test_a_file_name_given_to_the_api_says_how_to_read_it(tmp_path):
    image, soft = _lettered(tmp_path)
    with pytest.raises(
        clpde.InputError, match=r"pass an array \(to read a file use clpde.io.read_image\)"
    ):
        clpde.inpaint(str(tmp_path / "photo.png"), soft > 0)
    with pytest.raises(clpde.InputError, match="mask is .*a file name; pass an array"):
        clpde.inpaint(image, str(tmp_path / "mask.png"), channel_axis=-1)


def test_an_anti_aliased_mask_fills_its_soft_rim_and_says_so(tmp_path, capsys):
    image, soft = _lettered(tmp_path)
    rim = (soft > 0) & (soft <= 127)
    assert rim.sum() > 50  # the letters' anti-aliased edge, which a half-way cut left behind
    write_image(tmp_path / "mask.png", soft)
    out = tmp_path / "out.png"
    assert (
        main(["inpaint", str(tmp_path / "photo.png"), str(tmp_path / "mask.png"), "-o", str(out)])
        == 0
    )
    err = capsys.readouterr().err
    assert "grey levels" in err and "soft edges included" in err
    # the API's rule for the same mask as an array: nonzero = inpaint
    np.testing.assert_array_equal(read_image(out), clpde.inpaint(image, soft, channel_axis=-1))
