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
