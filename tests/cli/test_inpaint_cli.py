"""`clpde inpaint IMAGE MASK -o OUT [--gif ...]` and `clpde inpaint --demo -o OUTDIR`."""

import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import clpde
from clpde.cli import _inpaint_demo as inpaint_demo
from clpde.cli import main
from clpde.io.images import read_image, write_image


@pytest.fixture
def damaged(tmp_path):
    y, x = np.mgrid[0:40, 0:48]
    image = np.where(x + 0.5 * y > 30, 200, 60).astype(np.uint8)
    mask = np.zeros((40, 48), bool)
    mask[15:21, 10:40] = True
    spoiled = image.copy()
    spoiled[mask] = 255
    write_image(tmp_path / "photo.png", spoiled)
    write_image(tmp_path / "mask.png", mask.astype(np.uint8) * 255)
    return tmp_path / "photo.png", tmp_path / "mask.png", spoiled, mask, image


def test_inpaint_matches_the_library(tmp_path, damaged, capsys):
    photo, maskfile, spoiled, mask, truth = damaged
    out = tmp_path / "out.png"
    assert main(["inpaint", str(photo), str(maskfile), "-o", str(out), "--max-steps", "340"]) == 0
    result = read_image(out)
    np.testing.assert_array_equal(result, clpde.inpaint(spoiled, mask, max_steps=340))
    assert np.array_equal(result[~mask], spoiled[~mask])
    assert np.abs(result[mask].astype(float) - truth[mask]).mean() < 25
    assert "steps" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["mask.png", "out.png", "photo.png"]


def test_rgba_keeps_alpha_and_gif_shows_the_evolution(tmp_path, damaged):
    _, maskfile, spoiled, mask, _ = damaged
    rgba = np.dstack([spoiled, 255 - spoiled, spoiled // 2, np.full_like(spoiled, 180)])
    write_image(tmp_path / "rgba.png", rgba)
    out, gif = tmp_path / "out.png", tmp_path / "evolution.gif"
    assert (
        main(
            [
                "inpaint",
                str(tmp_path / "rgba.png"),
                str(maskfile),
                "-o",
                str(out),
                "--gif",
                str(gif),
                "--gif-every",
                "68",
                "--max-steps",
                "340",
                "--tol",
                "0",
                "--mean-tol",
                "0",
            ]
        )
        == 0
    )
    result = read_image(out)
    assert result.shape == rgba.shape and np.array_equal(result[..., 3], rgba[..., 3])
    assert np.array_equal(result[~mask], rgba[~mask])
    frames = iio.imread(gif, index=None)
    assert frames.shape[0] >= 6 and frames.shape[1:3] == mask.shape


@pytest.mark.parametrize(
    "args,match",
    [
        (["{photo}", "{small}", "-o", "{out}"], "same size"),
        (["{photo}", "-o", "{out}"], "give IMAGE and MASK"),
        (["{photo}", "{mask}", "-o", "{photo}"], ""),
        (["{photo}", "{mask}", "-o", "{out}", "--gif", "{dir}/a.png"], ".gif"),
        (["{photo}", "{mask}", "-o", "{out}", "--dt", "-1"], "dt"),
        (["--demo", "{photo}", "-o", "{dir}/demo"], "--demo"),
    ],
)
def test_errors_write_nothing(tmp_path, damaged, capsys, args, match):
    photo, maskfile, *_ = damaged
    write_image(tmp_path / "small.png", np.zeros((5, 5), np.uint8))
    names = {
        "photo": photo,
        "mask": maskfile,
        "small": tmp_path / "small.png",
        "out": tmp_path / "out.png",
        "dir": tmp_path,
    }
    before = sorted(os.listdir(tmp_path))
    assert main(["inpaint", *[a.format(**names) for a in args]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("clpde: error: ") and match in err[0]
    assert sorted(os.listdir(tmp_path)) == before


def test_demo_writes_the_pictures(tmp_path, monkeypatch):
    # The real demo inpaints a 512x512 photo; a corner of it keeps the test fast.
    full = inpaint_demo.damaged_astronaut
    monkeypatch.setattr(
        inpaint_demo, "damaged_astronaut", lambda: tuple(a[:96, :96] for a in full())
    )
    assert main(["inpaint", "--demo", "-o", str(tmp_path / "demo")]) == 0
    out = tmp_path / "demo" / "inpaint_demo"
    names = sorted(os.listdir(out))
    assert names == [
        "damaged.png",
        "inpaint_before_after.png",
        "inpainted.png",
        "mask.png",
        "original.png",
    ]
    original, damaged_, mask = (
        read_image(out / n) for n in ("original.png", "damaged.png", "mask.png")
    )
    restored = read_image(out / "inpainted.png")
    mask = mask > 0
    assert mask.any() and np.array_equal(restored[~mask], damaged_[~mask])
    assert (
        np.abs(restored[mask].astype(float) - original[mask]).mean()
        < np.abs(damaged_[mask].astype(float) - original[mask]).mean() / 2
    )


def test_the_demo_script_and_the_command_share_one_folder_and_rerun(tmp_path, monkeypatch, capsys):
    """The README's quickstart (examples/inpaint_demo.py) and its alternative (clpde inpaint
    --demo -o out/) write the same files into out/inpaint_demo, after each other too."""
    import runpy
    import sys

    full = inpaint_demo.damaged_astronaut
    monkeypatch.setattr(
        inpaint_demo, "damaged_astronaut", lambda: tuple(a[:64, :64] for a in full())
    )
    monkeypatch.chdir(tmp_path)
    script = str(Path(__file__).resolve().parents[2] / "examples" / "inpaint_demo.py")
    monkeypatch.setattr(sys, "argv", [script])

    def listing():
        return sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))

    runpy.run_path(script, run_name="__main__")
    first = listing()
    assert first == ["out", "out/inpaint_demo"] + sorted(
        f"out/inpaint_demo/{n}" for n in inpaint_demo.DEMO_FILES
    )
    assert main(["inpaint", "--demo", "-o", "out/"]) == 0
    assert "wrote 5 files to out/inpaint_demo" in capsys.readouterr().err
    assert listing() == first
    assert main(["inpaint", "--demo", "-o", "out"]) == 0  # its own output again
    runpy.run_path(script, run_name="__main__")
    assert listing() == first


def test_method_and_soft_mask(tmp_path, damaged, capsys):
    photo, maskfile, spoiled, mask, _ = damaged
    grey = (mask * 128).astype(np.uint8)  # about half damaged
    write_image(tmp_path / "soft.png", grey)
    out = tmp_path / "soft_out.png"
    assert (
        main(
            [
                "inpaint",
                str(photo),
                str(tmp_path / "soft.png"),
                "-o",
                str(out),
                "--soft-mask",
                "--method",
                "transport",
                "--max-steps",
                "68",
            ]
        )
        == 0
    )
    want = clpde.inpaint(spoiled, grey.astype(np.float32) / 255, method="transport", max_steps=68)
    np.testing.assert_array_equal(read_image(out), want)
    assert main(["inpaint", str(photo), str(maskfile), "-o", str(out), "--method", "paint"]) == 2
    assert "invalid choice: 'paint'" in capsys.readouterr().err


def test_demo_puts_its_psnr_beside_the_peers(tmp_path, monkeypatch, capsys):
    """the demo's PSNR had nothing to compare it with."""
    full = inpaint_demo.damaged_astronaut
    monkeypatch.setattr(
        inpaint_demo, "damaged_astronaut", lambda: tuple(a[:96, :96] for a in full())
    )
    assert main(["inpaint", "--demo", "-o", str(tmp_path / "demo")]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "PSNR inside the mask" in line and "scikit-image biharmonic" in line
    pytest.importorskip("cv2")
    assert "OpenCV Telea" in line and "OpenCV Navier-Stokes" in line
    original, damaged, mask = (a[:96, :96] for a in full())
    peers = inpaint_demo.peer_psnr(damaged, mask, original)
    assert all(15 < v < 40 for v in peers.values())  # real fills, not the damage (about 5 dB)
    assert inpaint_demo.psnr_in_mask(damaged, original, mask) < 12
