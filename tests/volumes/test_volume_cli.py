"""The command line on volumes: NIfTI and multi-page TIFF in, the same format out, with the
file's spacing used and kept (clpde/cli/volumes.py)."""

import numpy as np
import pytest

import clpde
from clpde.cli import main
from clpde.io import read_volume, write_volume
from clpde.volumes import inpaint_volume

pytest.importorskip("nibabel")


@pytest.fixture
def ball(rng):
    z, y, x = np.indices((12, 14, 16))
    clean = np.where((2 * (z - 6)) ** 2 + (y - 7) ** 2 + (x - 8) ** 2 < 30, 180, 40)
    return np.clip(clean + rng.normal(0, 15, clean.shape), 0, 255).astype(np.uint8)


def test_denoise_a_nifti_volume_with_its_spacing(ball, tmp_path):
    src, out = tmp_path / "vol.nii.gz", tmp_path / "out.nii.gz"
    write_volume(src, ball, spacing=(2, 1, 1))
    assert main(["denoise", str(src), str(out), "--weight", "0.1"]) == 0
    result, info = read_volume(out, with_info=True)
    assert result.dtype == np.uint8 and info.spacing == (2.0, 1.0, 1.0)
    expected = clpde.denoise_tv(ball, weight=0.1, spacing=(2, 1, 1))
    assert np.abs(result.astype(int) - expected).max() <= 1
    # the spacing was used: unit spacing gives another volume
    assert np.abs(clpde.denoise_tv(ball, weight=0.1).astype(int) - result).max() > 2


def test_the_output_as_a_flag_or_a_word_once(ball, tmp_path, capsys):
    """`clpde denoise vol.nii.gz -o out.nii.gz` (the issue's form) is the positional form;
    both or neither is one line."""
    src = tmp_path / "vol.nii.gz"
    write_volume(src, ball, spacing=(2, 1, 1))
    word, flag = tmp_path / "word.nii.gz", tmp_path / "flag.nii.gz"
    assert main(["denoise", str(src), str(word), "--weight", "0.1"]) == 0
    assert main(["denoise", str(src), "-o", str(flag), "--weight", "0.1"]) == 0
    assert np.array_equal(read_volume(word), read_volume(flag))
    capsys.readouterr()
    assert main(["denoise", str(src)]) == 2
    assert main(["diffuse", str(src), str(word), "-o", str(flag)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "as OUT or as -o OUT" in lines[0] and "both" in lines[1]


def test_inpaint_a_tiff_volume_with_a_tiff_mask(ball, tmp_path):
    src, mask_file, out = tmp_path / "vol.tif", tmp_path / "mask.tif", tmp_path / "out.tif"
    mask = np.zeros(ball.shape, bool)
    mask[4:8, 5:9, 6:10] = True
    write_volume(src, ball, spacing=(2, 1, 1))
    write_volume(mask_file, mask.astype(np.uint8) * 255)
    assert main(["inpaint", str(src), str(mask_file), "-o", str(out)]) == 0
    result = read_volume(out)
    assert (result == inpaint_volume(ball, mask, spacing=(2, 1, 1))).all()
    assert (result[~mask] == ball[~mask]).all()
    spectral = tmp_path / "spectral.tif"
    assert (
        main(["inpaint", str(src), str(mask_file), "-o", str(spectral), "--method", "spectral"])
        == 0
    )
    expect = inpaint_volume(ball, mask, spacing=(2, 1, 1), method="spectral")
    assert (read_volume(spectral) == expect).all()


def test_diffuse_a_volume_and_refuse_an_image_output(ball, tmp_path, capsys):
    src = tmp_path / "vol.tif"
    write_volume(src, ball)
    assert main(["diffuse", str(src), str(tmp_path / "d.tif"), "--flow", "tv"]) == 0
    assert main(["diffuse", str(src), str(tmp_path / "d.png")]) != 0
    assert "unsupported volume format" in capsys.readouterr().err


def test_inpaint_a_volume_refuses_image_only_options(ball, tmp_path, capsys):
    src = tmp_path / "vol.tif"
    write_volume(src, ball)
    args = ["inpaint", str(src), str(src), "-o", str(tmp_path / "o.tif")]
    assert main([*args, "--gif", str(tmp_path / "e.gif")]) != 0
    assert "no --gif" in capsys.readouterr().err
    assert main([*args, "--method", "coherence"]) != 0
    assert "or --method spectral; leave out --method coherence" in capsys.readouterr().err
