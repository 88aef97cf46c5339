"""The command line, run in-process on tiny images: results match the library, dtypes survive
the files, inputs are never overwritten and nothing is written when a run fails."""

import argparse
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import clpde
from clpde.cli import SUBCOMMANDS, build_parser, main
from clpde.io.images import read_image, write_image


@pytest.fixture
def grey(tmp_path, rng):
    xx = np.mgrid[:20, :24][1]
    image = np.clip(100 + 80 * (xx > 11) + rng.normal(0, 12, xx.shape), 0, 255).astype(np.uint8)
    path = tmp_path / "grey.png"
    write_image(path, image)
    return path, image


def _files(folder):
    return sorted(os.listdir(folder))


def _one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("clpde: error: "), err
    return err[0]


def test_subcommands_are_registered():
    assert {"devices", "diffuse", "denoise"} <= set(SUBCOMMANDS)
    for command in ("devices", "diffuse", "denoise"):
        assert main([command, "--help"]) == 0


def test_each_subcommands_summary_is_its_modules_own():
    """`clpde --help` shows SUBCOMMANDS' one-line help without loading the modules: it must
    say what each module's own parser says (`clpde COMMAND --help`, docs/command-line.md)."""
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert {a.dest: a.help for a in action._choices_actions} == SUBCOMMANDS
    assert list(action.choices) == list(SUBCOMMANDS)


def test_devices_lists_and_marks_the_device_in_use(capsys):
    assert main(["devices"]) == 0
    lines = capsys.readouterr().out.splitlines()
    marked = [line for line in lines if line.startswith("*")]
    assert len(marked) == 1 and "compute units" in marked[0]

    assert main(["devices", "--json", "--device", "cpu"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert len(listed) == len(clpde.devices())
    in_use = [d for d in listed if d["in_use"]]
    assert len(in_use) == 1 and in_use[0]["type"] == "cpu"
    assert {
        "name",
        "platform",
        "compute_units",
        "global_mem_bytes",
        "max_alloc_bytes",
        "fp64",
    } <= set(in_use[0])


def test_devices_unknown_device_fails(capsys):
    assert main(["devices", "--device", "no-such-device-xyz"]) == 2
    assert "no-such-device-xyz" in _one_error_line(capsys)


@pytest.mark.parametrize(
    "flow, extra, params",
    [
        ("heat", [], {}),
        (
            "perona-malik",
            ["--kappa", "0.1", "--edge", "rational"],
            {"kappa": 0.1, "edge": "rational"},
        ),
        ("tv", ["--eps", "0.1"], {"eps": 0.1}),
        ("curvature", [], {}),
    ],
)
def test_diffuse_matches_the_library(tmp_path, grey, flow, extra, params):
    path, image = grey
    out = tmp_path / "out.png"
    assert main(["diffuse", str(path), str(out), "--flow", flow, "--steps", "4", *extra]) == 0
    result = read_image(out)
    assert result.dtype == np.uint8 and result.shape == image.shape
    np.testing.assert_array_equal(result, clpde.diffuse(image, flow, steps=4, **params))
    assert not np.array_equal(result, image)
    assert _files(tmp_path) == ["grey.png", "out.png"]  # no temporary left behind


def test_float_tiff_stays_float(tmp_path, rng):
    image = rng.random((12, 10)).astype(np.float32) * 3 - 1
    write_image(tmp_path / "in.tif", image)
    assert (
        main(
            [
                "diffuse",
                str(tmp_path / "in.tif"),
                str(tmp_path / "out.tif"),
                "--steps",
                "3",
                "--dt",
                "0.2",
            ]
        )
        == 0
    )
    result = read_image(tmp_path / "out.tif")
    assert result.dtype == np.float32
    np.testing.assert_array_equal(result, clpde.diffuse(image, steps=3, dt=0.2))


def test_uint16_png_stays_uint16(tmp_path, rng):
    image = rng.integers(0, 65535, (9, 11)).astype(np.uint16)
    write_image(tmp_path / "in.png", image)
    assert (
        main(["diffuse", str(tmp_path / "in.png"), str(tmp_path / "out.png"), "--steps", "2"]) == 0
    )
    result = read_image(tmp_path / "out.png")
    assert result.dtype == np.uint16
    np.testing.assert_array_equal(result, clpde.diffuse(image, steps=2))


def test_colour_is_processed_per_channel_and_alpha_passes_through(tmp_path, rng):
    rgb = rng.integers(0, 256, (10, 12, 3)).astype(np.uint8)
    alpha = rng.integers(0, 256, (10, 12)).astype(np.uint8)
    write_image(tmp_path / "rgb.png", rgb)
    write_image(tmp_path / "rgba.png", np.dstack([rgb, alpha]))
    expected = clpde.diffuse(rgb, "heat", steps=3, channel_axis=-1)

    assert (
        main(["diffuse", str(tmp_path / "rgb.png"), str(tmp_path / "a.png"), "--steps", "3"]) == 0
    )
    np.testing.assert_array_equal(read_image(tmp_path / "a.png"), expected)

    assert (
        main(["diffuse", str(tmp_path / "rgba.png"), str(tmp_path / "b.png"), "--steps", "3"]) == 0
    )
    result = read_image(tmp_path / "b.png")
    assert result.shape == (10, 12, 4)
    np.testing.assert_array_equal(result[..., 3], alpha)
    np.testing.assert_array_equal(result[..., :3], expected)


def test_grey_with_alpha_keeps_alpha(tmp_path, rng):
    grey_alpha = rng.integers(0, 256, (8, 9, 2)).astype(np.uint8)
    write_image(tmp_path / "la.png", grey_alpha)
    assert main(["diffuse", str(tmp_path / "la.png"), str(tmp_path / "o.png"), "--steps", "2"]) == 0
    result = read_image(tmp_path / "o.png")
    np.testing.assert_array_equal(result[..., 1], grey_alpha[..., 1])
    np.testing.assert_array_equal(result[..., 0], clpde.diffuse(grey_alpha[..., 0], steps=2))


@pytest.mark.parametrize("option", [["--sigma", "12"], ["--weight", "0.1"]])
def test_denoise_matches_the_library(tmp_path, grey, capsys, option):
    path, image = grey
    out = tmp_path / "out.png"
    assert main(["denoise", str(path), str(out), *option, "--max-steps", "60"]) == 0
    assert "denoise:" in capsys.readouterr().err
    result = read_image(out)
    assert result.dtype == np.uint8
    key, value = option[0][2:], float(option[1])
    np.testing.assert_array_equal(result, clpde.denoise_tv(image, max_steps=60, **{key: value}))
    assert _files(tmp_path) == ["grey.png", "out.png"]


def test_denoise_colour_with_sigma_and_the_gradient_method(tmp_path, rng):
    rgb = rng.integers(0, 256, (14, 15, 3)).astype(np.uint8)
    write_image(tmp_path / "in.png", rgb)
    assert (
        main(
            [
                "denoise",
                str(tmp_path / "in.png"),
                str(tmp_path / "a.png"),
                "--sigma",
                "20",
                "--max-steps",
                "30",
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(
        read_image(tmp_path / "a.png"),
        clpde.denoise_tv(rgb, sigma=20, channel_axis=-1, max_steps=30),
    )
    assert (
        main(
            [
                "denoise",
                str(tmp_path / "in.png"),
                str(tmp_path / "b.png"),
                "--method",
                "gradient",
                "--eps",
                "0.05",
                "--weight",
                "0.2",
                "--max-steps",
                "30",
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(
        read_image(tmp_path / "b.png"),
        clpde.denoise_tv(
            rgb, weight=0.2, channel_axis=-1, method="gradient", eps=0.05, max_steps=30
        ),
    )


def test_denoise_colour_jpeg(tmp_path, rng):
    rgb = rng.integers(0, 256, (16, 16, 3)).astype(np.uint8)
    write_image(tmp_path / "in.jpg", rgb)
    assert (
        main(
            [
                "denoise",
                str(tmp_path / "in.jpg"),
                str(tmp_path / "out.jpg"),
                "--weight",
                "0.2",
                "--max-steps",
                "40",
            ]
        )
        == 0
    )
    result = read_image(tmp_path / "out.jpg")
    assert result.dtype == np.uint8 and result.shape == rgb.shape


def test_denoise_sigma_and_weight_are_exclusive(grey, tmp_path):
    path, _ = grey
    assert (
        main(["denoise", str(path), str(tmp_path / "o.png"), "--sigma", "1", "--weight", "1"]) == 2
    )
    assert _files(tmp_path) == ["grey.png"]


def test_refuses_to_overwrite_its_input(grey, tmp_path, capsys, monkeypatch):
    path, _ = grey
    before = path.read_bytes()
    monkeypatch.chdir(tmp_path)
    for command in (["diffuse", "--steps", "1"], ["denoise", "--max-steps", "5"]):
        assert main([command[0], str(path), "grey.png", *command[1:]]) == 2
        assert "never overwrites" in _one_error_line(capsys)
    assert path.read_bytes() == before
    assert _files(tmp_path) == ["grey.png"]


@pytest.mark.parametrize(
    "args, words",
    [
        (["diffuse", "IN", "out.png", "--dt", "0.3"], "stability limit 0.25"),
        (["diffuse", "IN", "out.png", "--flow", "tv", "--eps", "0.01", "--dt", "1"], "stability"),
        (["diffuse", "IN", "out.png", "--device", "no-such-device-xyz"], "no-such-device-xyz"),
        (["denoise", "IN", "out.png", "--device", "99"], "out of range"),
        (["diffuse", "missing.png", "out.png"], "missing.png does not exist"),
        (["diffuse", "IN", "out.png", "--kappa", "0.1"], "--kappa applies to --flow perona-malik"),
        (["diffuse", "IN", "out.png", "--steps", "-1"], "steps"),
        (["diffuse", "IN", "out.bmp"], "unsupported image format"),
        (["diffuse", "IN", "no/such/folder/out.png"], "does not exist"),
        (["denoise", "IN", "out.jpg", "--sigma", "-2"], "sigma"),
        (["denoise", "IN", "out.png", "--eps", "0.1"], "--eps applies to --method gradient"),
    ],
)
def test_errors_are_one_line_and_write_nothing(grey, tmp_path, capsys, monkeypatch, args, words):
    path, _ = grey
    monkeypatch.chdir(tmp_path)
    args = [str(path) if a == "IN" else a for a in args]
    assert main(args) == 2
    assert words in _one_error_line(capsys)
    assert _files(tmp_path) == ["grey.png"]


def test_float_input_to_png_fails_before_any_work(tmp_path, capsys):
    write_image(tmp_path / "in.tif", np.zeros((5, 5), np.float32))
    assert main(["diffuse", str(tmp_path / "in.tif"), str(tmp_path / "out.png")]) == 2
    assert "write a .tif" in _one_error_line(capsys)
    assert _files(tmp_path) == ["in.tif"]


def test_usage_errors_exit_2(grey, tmp_path, capsys):
    path, _ = grey
    assert main(["diffuse", str(path), str(tmp_path / "o.png"), "--flow", "blur"]) == 2
    assert "invalid choice" in capsys.readouterr().err
    assert main([]) == 2
    assert main(["no-such-command"]) == 2
    assert _files(tmp_path) == ["grey.png"]


def test_python_dash_m_clpde(grey, tmp_path):
    path, image = grey
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "clpde",
            "diffuse",
            str(path),
            str(tmp_path / "o.png"),
            "--steps",
            "2",
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    np.testing.assert_array_equal(read_image(tmp_path / "o.png"), clpde.diffuse(image, steps=2))
    run = subprocess.run(
        [sys.executable, "-m", "clpde", "diffuse", str(path), str(path)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert run.returncode == 2
    assert run.stderr.strip().startswith("clpde: error: ")


def test_progress_bar_only_on_a_terminal(grey, tmp_path, capsys, monkeypatch):
    path, _ = grey
    assert main(["diffuse", str(path), str(tmp_path / "a.png"), "--steps", "60"]) == 0
    assert "step" not in capsys.readouterr().err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["diffuse", str(path), str(tmp_path / "b.png"), "--steps", "60"]) == 0
    assert "60/60" in capsys.readouterr().err
