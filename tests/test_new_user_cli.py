"""What a new user hit (issue 11), through the command line: each case as the user typed it,
with a one-line `clpde: error: ...` (or warning) that gives command-line advice."""

import os
import sys

import numpy as np
import pytest

import clpde
from clpde.cli import main
from clpde.io import read_image, write_image


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
    residual = float(capsys.readouterr().err.split("residual std ")[1].split()[0])
    assert residual == pytest.approx(15, rel=0.2)


# ---- 2 and 7. one rule for output folders -------------------------------------------------
def test_regions_rerun_holds_only_its_own_files(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["regions", "merge", "-o", str(out), "--spacing", "0.1", "--size", "32"]
    assert main([*args, "--saves", "2"]) == 0
    capsys.readouterr()
    assert main([*args, "--saves", "1"]) == 2
    assert "is not empty (4 entries); choose a new folder, or give --overwrite" in _one_error_line(capsys)
    assert main([*args, "--saves", "1", "--overwrite"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["regions.png", "regions_0.ply", "regions_1.ply"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging or old folder left


@pytest.mark.parametrize("command", [
    ["surface", "heat", "sphere"],
    ["regions", "merge"],
    ["inpaint", "--demo"],
    ["track", "FRAMES", "--init", "MASK"],
])
def test_every_folder_command_has_one_rule(tmp_path, capsys, command):
    """Refused before any work: a non-empty folder without --overwrite, a folder with files
    clpde does not write even with it, and a missing parent (create it first)."""
    frames = tmp_path / "frames"
    frames.mkdir()
    write_image(frames / "f1.png", np.zeros((8, 8), np.uint8))
    write_image(tmp_path / "mask.png", np.zeros((8, 8), np.uint8))
    command = [str(frames) if a == "FRAMES" else str(tmp_path / "mask.png") if a == "MASK" else a
               for a in command]
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.png").write_bytes(b"old")
    assert main([*command, "-o", str(out)]) == 2
    assert "give --overwrite" in _one_error_line(capsys)
    (out / "notes.txt").write_text("mine")
    assert main([*command, "-o", str(out), "--overwrite"]) == 2
    assert "'notes.txt', which clpde does not write" in _one_error_line(capsys)
    assert main([*command, "-o", str(tmp_path / "no" / "such")]) == 2
    assert "does not exist; create it first" in _one_error_line(capsys)
    assert sorted(os.listdir(out)) == ["notes.txt", "old.png"]
    assert not (tmp_path / "no").exists()


# ---- 3. lossy and grey masks ----------------------------------------------------------------
def test_inpaint_reads_a_jpeg_mask_at_half_range_and_warns(noisy_png, tmp_path, capsys):
    from PIL import Image

    path, image = noisy_png
    truth = np.zeros(image.shape, bool)
    truth[10:12, 5:40] = truth[25:27, 5:40] = True
    Image.fromarray(truth.astype(np.uint8) * 255).save(tmp_path / "mask.jpg", quality=75)
    assert main(["inpaint", str(path), str(tmp_path / "mask.jpg"), "-o", str(tmp_path / "o.png"),
                 "--max-steps", "20", "--levels", "1"]) == 0
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
    assert len(listed.out.splitlines()) == len(clpde.devices())  # the list, nothing marked
    assert not [line for line in listed.out.splitlines() if line.startswith("*")]
    monkeypatch.delenv("CLPDE_DEVICE")
    assert main(["devices"]) == 0
