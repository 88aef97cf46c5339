"""What a new user hit on a fresh clone, and what photo restorers and scikit-image users
expect next: each case as typed, through the command line and the API."""

import argparse
import importlib
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import clpde
from clpde.cli import build_parser, main
from clpde.imagedata import InputError, grow_mask
from clpde.io import read_image, write_image

ROOT = Path(__file__).resolve().parents[2]


def _error_line(capsys, prefix="clpde"):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(prefix) and ": error: " in err[0], err
    return err[0]


def _ramp_rgb16():
    yy, xx = np.mgrid[:40, :48]
    return np.dstack([xx * 1300, yy * 1500, (xx + yy) * 700]).astype(np.uint16)


def _square_mask(shape=(40, 48)):
    mask = np.zeros(shape, np.uint8)
    mask[15:22, 10:30] = 255
    return mask


# ---- 16-bit colour PNG through the command line -------------------------------------------
def test_inpaint_keeps_a_16_bit_colour_png_at_16_bits(tmp_path, capsys):
    image = _ramp_rgb16()
    write_image(tmp_path / "rgb16.png", image)
    write_image(tmp_path / "mask.png", _square_mask())
    assert read_image(tmp_path / "rgb16.png").dtype == np.uint16
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "rgb16.png"),
                str(tmp_path / "mask.png"),
                "-o",
                str(tmp_path / "out.tif"),
            ]
        )
        == 0
    )
    out = read_image(tmp_path / "out.tif")
    assert out.dtype == np.uint16 and out.shape == image.shape
    inside = _square_mask() > 0
    np.testing.assert_array_equal(out[~inside], image[~inside])  # not cut to 8 bits
    # the fill continues the ramps at 16 bits (8 bits scaled up would be multiples of 257)
    assert int(np.abs(out[inside].astype(int) - image[inside]).max()) < 0.1 * 65535
    assert (out[inside] % 257 != 0).mean() > 0.9


# ---- an empty mask --------------------------------------------------------------------------
def test_an_empty_mask_warns_and_reports_no_method(tmp_path, capsys):
    image = np.tile(np.arange(48, dtype=np.uint8) * 5, (40, 1))
    with pytest.warns(UserWarning, match="mask is empty, so nothing was filled") as caught:
        out, info = clpde.inpaint(image, np.zeros(image.shape, bool), return_info=True)
    assert caught[0].filename == __file__  # attributed to the caller's line
    assert info.method is None and info.boxes == []
    np.testing.assert_array_equal(out, image)
    assert out is not image
    with pytest.warns(UserWarning, match="inverted"):
        clpde.Inpainting(image, np.zeros(image.shape, np.uint8))

    write_image(tmp_path / "in.png", image)
    write_image(tmp_path / "empty.png", np.zeros(image.shape, np.uint8))
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "in.png"),
                str(tmp_path / "empty.png"),
                "-o",
                str(tmp_path / "out.png"),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "clpde: warning: the mask is empty, so nothing was filled" in err
    assert "method" not in err and "0 pixels to fill" in err
    np.testing.assert_array_equal(read_image(tmp_path / "out.png"), image)


# ---- batch: a pattern that matches nothing ----------------------------------------------------
def test_batch_pattern_matching_nothing_is_a_usage_error_that_creates_nothing(tmp_path, capsys):
    pattern = str(tmp_path / "scans" / "*.png")  # the shell passes it on as typed
    assert main(["batch", "denoise", pattern, "-o", str(tmp_path / "out")]) == 2
    assert "matches no file" in _error_line(capsys)
    assert os.listdir(tmp_path) == []
    with pytest.raises(InputError, match="matches no file"):
        clpde.batch("denoise", [pattern], tmp_path / "out")
    assert os.listdir(tmp_path) == []


def test_batch_expands_a_quoted_pattern(tmp_path):
    from clpde.scale.batch import expand_inputs

    for name in ("b.png", "a.png", "c.tif"):
        write_image(tmp_path / name, np.zeros((4, 4), np.uint8))
    assert expand_inputs([tmp_path / "*.png", tmp_path / "c.tif"]) == [
        str(tmp_path / "a.png"),
        str(tmp_path / "b.png"),
        str(tmp_path / "c.tif"),
    ]


# ---- the output is checked before any work ------------------------------------------------------
@pytest.fixture
def read_only_folder(tmp_path):
    """A folder nobody can create files in: read-only permissions, and for root (whom
    permissions do not stop) the immutable attribute."""
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    immutable = False
    try:
        (folder / "probe_double").touch()
    except OSError:
        pass
    else:
        (folder / "probe_double").unlink()
        immutable = (
            subprocess.run(
                ["chattr", "+i", str(folder)], capture_output=True, check=False
            ).returncode
            == 0
            if shutil.which("chattr")
            else False
        )
        if not immutable:
            folder.chmod(0o755)
            pytest.skip("cannot make a folder read-only here (root without chattr +i)")
    yield folder
    if immutable:
        subprocess.run(["chattr", "-i", str(folder)], check=False)
    folder.chmod(0o755)


def _never_compute(monkeypatch):
    """Make every computation fail loudly: a check that comes after it is too late."""

    def computed(*args, **kwargs):
        raise AssertionError("computed before the output was checked")

    # the command table's own names (clpde.scale.file_tasks), where the commands call them
    for module, name in [
        ("clpde.scale.file_tasks", "diffuse"),
        ("clpde.scale.file_tasks", "denoise_tv"),
        ("clpde.scale.file_tasks", "inpaint"),
        ("clpde.scale.file_tasks", "track"),
        ("clpde.scale.cluster", "start_cluster"),
        ("clpde.io.frames", "read_frames"),
    ]:
        monkeypatch.setattr(importlib.import_module(module), name, computed)


def _commands(tmp_path, out_dir):
    image, mask = tmp_path / "in.png", tmp_path / "mask.png"
    write_image(image, _ramp_rgb16())
    write_image(mask, _square_mask())
    return {
        "diffuse": ["diffuse", str(image), str(out_dir / "out.png"), "--steps", "1"],
        "denoise": ["denoise", str(image), str(out_dir / "out.png")],
        "inpaint": ["inpaint", str(image), str(mask), "-o", str(out_dir / "out.tif")],
        "inpaint --gif": [
            "inpaint",
            str(image),
            str(mask),
            "-o",
            str(tmp_path / "o.tif"),
            "--gif",
            str(out_dir / "evolution.gif"),
        ],
        "track": ["track", str(image), "--init", str(mask), "-o", str(out_dir / "t")],
        "regions": ["regions", "merge", "-o", str(out_dir / "r")],
        "surface": ["surface", "heat", "sphere", "-o", str(out_dir / "s")],
        "batch": ["batch", "denoise", str(image), "-o", str(out_dir / "b")],
    }


COMMANDS = [
    "diffuse",
    "denoise",
    "inpaint",
    "inpaint --gif",
    "track",
    "regions",
    "surface",
    "batch",
]


@pytest.mark.parametrize("command", COMMANDS)
def test_an_unwritable_output_folder_is_refused_before_any_work(
    tmp_path, read_only_folder, monkeypatch, capsys, command
):
    argv = _commands(tmp_path, read_only_folder)[command]
    _never_compute(monkeypatch)
    assert main(argv) == 2
    line = _error_line(capsys)
    assert "is not writable" in line and str(read_only_folder) in line
    assert os.listdir(read_only_folder) == []


@pytest.mark.parametrize("command", [c for c in COMMANDS if c != "batch"])  # batch: mkdir -p
def test_a_missing_output_folder_is_refused_before_any_work(tmp_path, monkeypatch, capsys, command):
    argv = _commands(tmp_path, tmp_path / "missing" / "deeper")[command]
    _never_compute(monkeypatch)
    assert main(argv) == 2
    assert "does not exist" in _error_line(capsys)
    assert not (tmp_path / "missing").exists()


def test_an_output_that_is_a_folder_or_of_no_known_format_is_refused(tmp_path, monkeypatch, capsys):
    argv = _commands(tmp_path, tmp_path)
    _never_compute(monkeypatch)
    (tmp_path / "folder.png").mkdir()
    assert main(["diffuse", argv["diffuse"][1], str(tmp_path / "folder.png")]) == 2
    assert "is a folder" in _error_line(capsys)
    assert main(["denoise", argv["diffuse"][1], str(tmp_path / "out.bmp")]) == 2
    assert "unsupported image format" in _error_line(capsys)


# ---- help, docs and messages that agree with the code -------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ["inpaint", "a.png"],  # -o missing
        ["diffuse", "a.png", "b.png", "--steps", "x"],  # a bad value
        ["denoise", "a.png", "b.png", "--sigma", "1", "--weight", "2"],  # exclusive options
        ["inpaint", "a.png", "m.png", "-o", "o.png", "--method", "paint"],
        ["batch", "inpaint"],
        [],
        ["no-such-command"],
    ],
)
def test_usage_errors_are_one_line(capsys, argv):
    assert main(argv) == 2
    line = _error_line(capsys)
    assert line.endswith("--help`") and "usage:" not in line


def test_inpaint_help_describes_the_default_method(capsys):
    from clpde.inpainting.registry import DEFAULT

    assert main(["inpaint", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    description = text[text.index("Fill the pixels") : text.index("positional arguments")]
    # (argparse wraps lines after hyphens: "self- validated" once the lines are joined)
    description = description.replace("- ", "-")
    assert f"The default method is {DEFAULT} (frequency-selective)" in description
    assert "--method auto is the self-validated choice" in description
    assert "--method transport is the thesis's scheme" in description


def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def test_every_option_of_every_command_is_in_the_command_line_page():
    page = (ROOT / "docs" / "command-line.md").read_text()
    sections = dict(re.findall(r"^### `clpde (\S+)`.*?\n(.*?)(?=^### |^## |\Z)", page, re.S | re.M))
    missing = []
    for name, sub in _subparsers().items():
        assert name in sections, f"docs/command-line.md has no section ### `clpde {name}`"
        for action in sub._actions:
            for option in action.option_strings:
                if (
                    option.startswith("--")
                    and option not in ("--help", "--device")
                    and not re.search(rf"`{re.escape(option)}[` ]", sections[name])
                ):
                    missing.append(f"clpde {name} {option}")
    assert not missing, f"options missing from docs/command-line.md: {missing}"


def test_time_step_messages_name_no_python_none(tmp_path, capsys):
    write_image(tmp_path / "in.png", np.eye(16, dtype=np.uint8) * 200)
    assert main(["diffuse", str(tmp_path / "in.png"), str(tmp_path / "o.png"), "--dt", "10"]) == 2
    line = _error_line(capsys)
    assert "None" not in line and "stability limit" in line


def test_a_file_that_is_no_image_gets_a_clean_line(tmp_path, capsys):
    (tmp_path / "notes.png").write_text("my notes, not a picture\n")
    assert main(["diffuse", str(tmp_path / "notes.png"), str(tmp_path / "o.png")]) == 2
    line = _error_line(capsys)
    assert "notes.png" in line and ".png, .tif/.tiff and .jpg/.jpeg" in line
    assert "pillow" not in line.lower() and "uri" not in line
    assert sorted(os.listdir(tmp_path)) == ["notes.png"]


# ---- growing masks ------------------------------------------------------------------------
@pytest.mark.parametrize("radius", [1, 2, 3, 5, 2.5])
def test_grow_of_a_pixel_is_a_disc(radius):
    dot = np.zeros((15, 15), bool)
    dot[7, 7] = True
    yy, xx = np.mgrid[:15, :15]
    disc = (yy - 7) ** 2 + (xx - 7) ** 2 <= radius**2
    grown = grow_mask(dot, radius)
    assert grown.dtype == bool
    np.testing.assert_array_equal(grown, disc)
    assert clpde.grow_mask is grow_mask


@pytest.mark.parametrize("radius", [1, 4.5, 13])
def test_grow_is_exact_across_its_strips(rng, radius):
    from scipy import ndimage

    mask = rng.random((700, 90)) < 0.002  # strips of 256 rows: the disc crosses them
    mask[255, 40] = mask[256, 70] = mask[0, 0] = mask[699, 89] = True
    np.testing.assert_array_equal(
        grow_mask(mask, radius), ndimage.distance_transform_edt(~mask) <= radius
    )


def test_grow_keeps_soft_values_and_gives_the_ring_full_damage():
    soft = np.zeros((9, 9), np.float32)
    soft[4, 3:6] = [0.25, 0.5, 1.0]
    before = soft.copy()
    grown = grow_mask(soft, 1)
    np.testing.assert_array_equal(soft, before)  # the input is not modified
    assert grown.dtype == np.float32
    np.testing.assert_array_equal(grown[4, 3:6], [0.25, 0.5, 1.0])  # kept
    ring = (grow_mask(soft > 0, 1)) & ~(soft > 0)
    assert (grown[ring] == 1).all() and (grown[~ring & ~(soft > 0)] == 0).all()


def test_grow_of_a_0_255_mask_and_the_limits():
    mask = np.zeros((7, 7), np.uint8)
    mask[3, 3] = 255
    grown = grow_mask(mask, 1)
    assert grown.dtype == np.uint8 and set(np.unique(grown)) == {0, 255}
    assert int((grown == 255).sum()) == 5
    same = grow_mask(mask, 0)
    np.testing.assert_array_equal(same, mask)
    assert same is not mask
    for bad in (-1, -0.5, float("nan"), True, "2"):
        with pytest.raises(InputError, match="number of pixels >= 0"):
            grow_mask(mask, bad)
    with pytest.raises(InputError, match="2-D"):
        grow_mask(np.zeros((3, 3, 3), bool), 1)


def test_inpaint_grow_is_inpaint_of_the_grown_mask(tmp_path, capsys):
    image = np.tile(np.linspace(0, 250, 48), (40, 1)).astype(np.uint8)
    image[:, 24:] = 250 - image[:, 24:]
    mask = _square_mask() > 0
    grown = grow_mask(mask, 2)
    direct, info = clpde.inpaint(image, mask, grow=2, return_info=True)
    np.testing.assert_array_equal(direct, clpde.inpaint(image, grown))
    assert info.omega_pixels == int(grown.sum())
    soft = np.where(mask, 0.5, 0.0)
    job = clpde.Inpainting(image, soft, grow=2)
    assert job.mask.sum() == grown.sum() and (job.softness[grown & ~mask] == 1).all()

    write_image(tmp_path / "in.png", image)
    write_image(tmp_path / "mask.png", mask.astype(np.uint8) * 255)
    write_image(tmp_path / "grown.png", grown.astype(np.uint8) * 255)
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "in.png"),
                str(tmp_path / "mask.png"),
                "-o",
                str(tmp_path / "a.png"),
                "--grow",
                "2",
            ]
        )
        == 0
    )
    assert f"inpaint: {int(grown.sum())} pixels" in capsys.readouterr().err
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "in.png"),
                str(tmp_path / "grown.png"),
                "-o",
                str(tmp_path / "b.png"),
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(read_image(tmp_path / "a.png"), read_image(tmp_path / "b.png"))
    capsys.readouterr()
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "in.png"),
                str(tmp_path / "mask.png"),
                "-o",
                str(tmp_path / "c.png"),
                "--grow",
                "-1",
            ]
        )
        == 2
    )
    assert "--grow must be a number of pixels >= 0, not -1" in _error_line(capsys)


def test_seed_on_the_command_line_is_the_exemplars_seed(tmp_path):
    rng = np.random.default_rng(4)
    image = (rng.random((40, 48)) * 255).astype(np.uint8)  # texture: the seed matters
    mask = _square_mask() > 0
    write_image(tmp_path / "in.png", image)
    write_image(tmp_path / "mask.png", mask.astype(np.uint8) * 255)
    outs = {}
    for seed in (1, 2):
        assert (
            main(
                [
                    "inpaint",
                    str(tmp_path / "in.png"),
                    str(tmp_path / "mask.png"),
                    "-o",
                    str(tmp_path / f"s{seed}.png"),
                    "--method",
                    "exemplar",
                    "--seed",
                    str(seed),
                ]
            )
            == 0
        )
        outs[seed] = read_image(tmp_path / f"s{seed}.png")
        np.testing.assert_array_equal(
            outs[seed], clpde.inpaint(image, mask, method="exemplar", seed=seed)
        )
    assert not np.array_equal(outs[1], outs[2])


# ---- scikit-image users: dir() and bool images ------------------------------------------------
def test_dir_lists_the_public_api_only():
    names = dir(clpde)
    assert names == sorted(set(clpde.__all__) | set(clpde.PUBLIC_MODULES) | {"__version__"})
    for internal in (
        "rof",
        "planar",
        "runtime",
        "imagedata",
        "tiled",
        "fields",
        "levelset",
        "colour",
        "multiresolution",
        "regions_mesh",
        "_progress",
        "_state",
    ):
        assert internal not in names
    for name in names:
        getattr(clpde, name)  # everything listed is there
    assert isinstance(clpde.inpainting, type(clpde)) and clpde.inpainting.available()
    assert importlib.import_module("clpde.planar.rof").denoise_tv is clpde.denoise_tv


def _disc(n=40, r=12):
    yy, xx = np.mgrid[:n, :n]
    return (yy - n // 2) ** 2 + (xx - n // 2) ** 2 <= r**2


def test_bool_images_are_binary_in_and_out():
    disc = _disc()
    hole = np.zeros(disc.shape, bool)
    hole[17:23, 5:14] = True  # across the disc's left edge
    filled = clpde.inpaint(disc, hole)
    assert filled.dtype == bool
    np.testing.assert_array_equal(filled[~hole], disc[~hole])
    assert (filled[hole] == disc[hole]).mean() >= 0.9
    smooth = clpde.diffuse(disc, "heat", steps=5)
    assert smooth.dtype == bool and (smooth == disc).mean() > 0.98
    noisy = disc.copy()
    noisy[::7, ::5] ^= True  # salt and pepper
    clean = clpde.denoise_tv(noisy, weight=0.3)
    assert clean.dtype == bool and (clean == disc).mean() > (noisy == disc).mean()


# ---- Ctrl-C at any moment ------------------------------------------------------------------------
def _interrupt(argv, cwd, when):
    """Run `python -m clpde ARGV` in its own process group and send the whole group SIGINT,
    as a terminal's Ctrl-C does: when "loading", the moment numpy is loaded (clpde's
    package is loading: it loads numpy after its Ctrl-C handler; before, Python itself is
    starting, which no program can quiet), or "workers", the moment the first Dask worker
    process exists (the cluster is starting)."""
    import psutil

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [sys.executable, "-m", "clpde", *argv],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            process = psutil.Process(proc.pid)
            if when == "workers":
                if any(
                    "spawn_main" in " ".join(c.cmdline())
                    for c in process.children(recursive=True)
                    if c.is_running()
                ):
                    break
            elif any("_multiarray_umath" in m.path for m in process.memory_maps()):
                break
            time.sleep(0.01)
        else:
            pytest.fail(f"the moment {when!r} did not come")
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    # 130 = 128 + SIGINT: what a shell reports for a process that Ctrl-C stopped, too
    assert proc.returncode in (130, -signal.SIGINT), err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clpde") and "interrupted" in lines[0], err
    return lines[0]


@pytest.fixture
def film_inputs(tmp_path):
    rng = np.random.default_rng(2)
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(4):
        write_image(frames / f"f{k}.png", (rng.random((32, 40, 3)) * 255).astype(np.uint8))
    mask = np.zeros((32, 40), np.uint8)
    mask[10:14, 5:30] = 255
    write_image(tmp_path / "mask.png", mask)
    write_image(tmp_path / "in.png", (rng.random((32, 40)) * 255).astype(np.uint8))
    return tmp_path


def test_ctrl_c_while_clpde_loads_is_one_line(film_inputs):
    _interrupt(["diffuse", "in.png", "out.png"], film_inputs, "loading")
    assert not (film_inputs / "out.png").exists()


@pytest.mark.parametrize("command", ["batch", "film"])
def test_ctrl_c_while_the_dask_cluster_starts_is_one_line(film_inputs, command):
    argv = (
        ["batch", "denoise", "in.png", "-o", "out", "--workers", "2"]
        if command == "batch"
        else ["inpaint", "frames", "mask.png", "-o", "film.mp4", "--workers", "2"]
    )
    line = _interrupt(argv, film_inputs, "workers")
    assert "interrupted" in line
    assert not (film_inputs / "film.mp4").exists()
    leftovers = [p.name for p in film_inputs.rglob("*.part")]
    assert not leftovers


def test_the_command_line_page_says_what_the_parsers_say():
    """docs/command-line.md's option lists are written from the parsers (their summaries,
    choices and defaults), and every `--option {a,b}` choice list in the docs and the README
    is the parser's own."""
    from clpde.cli._options_doc import PAGE, options_markdown, page_section

    page = PAGE.read_text()
    assert page_section(page) == options_markdown(), (
        "docs/command-line.md's options differ from the parsers: run "
        "`python -m clpde.cli._options_doc`"
    )
    choices = {}
    for sub in _subparsers().values():
        for action in sub._actions:
            for option in action.option_strings:
                if action.choices:
                    choices.setdefault(option, set()).add(",".join(action.choices))
    stale = [
        f"{name}: {option} {{{listed}}}"
        for name in ("README.md", "docs/command-line.md", "docs/batch.md")
        for option, listed in re.findall(r"(--[\w-]+) \{([^}]*)\}", (ROOT / name).read_text())
        if listed not in choices.get(option, {listed})
    ]
    assert not stale, f"choice lists that differ from the parsers: {stale}"
