"""The default noise estimate of denoise_tv: numpy only (no PyWavelets), checked against the
known sigma of noise added to several kinds of images."""

import sys

import numpy as np
import pytest
from skimage import color, data, img_as_float

import clpde
from clpde.errors import InputError
from clpde.planar.rof import estimate_sigma

IMAGES = {
    "camera": lambda: img_as_float(data.camera()),
    "astronaut": lambda: color.rgb2gray(data.astronaut()),
    "coins": lambda: img_as_float(data.coins()),
    "text": lambda: img_as_float(data.text()),
    "checkerboard": lambda: img_as_float(data.checkerboard()),
}


@pytest.mark.parametrize("name", sorted(IMAGES))
@pytest.mark.parametrize("sigma", [0.05, 0.1, 0.2])
def test_estimate_matches_the_added_noise(name, sigma):
    clean = IMAGES[name]()
    noisy = clean + np.random.default_rng(1).normal(0, sigma, clean.shape)
    # float images are in their own units: the estimate must not depend on the range
    assert estimate_sigma(noisy) == pytest.approx(sigma, rel=0.1)
    assert estimate_sigma(100 * noisy) == pytest.approx(100 * sigma, rel=0.1)


def test_estimate_in_uint8_units_and_per_channel():
    clean = data.astronaut().astype(np.float64)
    noisy = np.clip(
        clean + np.random.default_rng(2).normal(0, [6, 12, 24], clean.shape), 0, 255
    ).astype(np.uint8)
    actual = (noisy - clean).std(axis=(0, 1))  # what clipping left of the noise
    np.testing.assert_allclose(estimate_sigma(noisy, channel_axis=-1), actual, rtol=0.1)


def test_default_denoise_needs_no_pywavelets(monkeypatch):
    monkeypatch.setitem(sys.modules, "pywt", None)  # as on a fresh install: import pywt fails
    clean = img_as_float(data.camera())[::4, ::4]
    noisy = clean + np.random.default_rng(3).normal(0, 0.1, clean.shape)
    result, info = clpde.denoise_tv(noisy, return_info=True)
    # sigma was estimated near 0.1: the residual variance tends to it
    assert np.sqrt(info.residual_variance[0]) == pytest.approx(0.1, rel=0.15)
    assert np.abs(result - clean).mean() < 0.6 * np.abs(noisy - clean).mean()


def test_too_small_to_estimate():
    with pytest.raises(InputError, match="give sigma or weight"):
        clpde.denoise_tv(np.zeros((2, 5)))


@pytest.fixture
def noisy_rgb():
    """An 8-bit colour photo with noise of 10 grey levels (the estimate reads about 10)."""
    clean = data.astronaut()[100:260, 100:260].astype(float)
    noisy = clean + np.random.default_rng(2).normal(0, 10, clean.shape)
    return np.clip(noisy, 0, 255).round().astype(np.uint8)


def test_sigma_far_above_the_estimate_warns(noisy_rgb, recwarn):
    """Issue 33 item 11: a given sigma more than twice every channel's estimate over-smooths;
    denoise_tv says so, naming the estimates. Near the estimate it says nothing."""
    with pytest.warns(UserWarning, match=r"sigma 25 is more than 2 times the noise estimated"):
        clpde.denoise_tv(noisy_rgb, sigma=25, channel_axis=-1, max_steps=5)
    clpde.denoise_tv(noisy_rgb, sigma=12, channel_axis=-1, max_steps=5)
    assert not [w for w in recwarn if "estimated" in str(w.message)]


def test_sigma_far_above_the_estimate_warns_on_the_command_line(noisy_rgb, tmp_path, capsys):
    from clpde.cli import main
    from clpde.io.images import write_image

    path, out = tmp_path / "noisy.png", tmp_path / "out.png"
    write_image(path, noisy_rgb)
    assert main(["denoise", str(path), str(out), "--sigma", "30", "--max-steps", "5"]) == 0
    err = capsys.readouterr().err
    assert "clpde: warning: sigma 30 is more than 2 times the noise estimated" in err
    assert "leave sigma out to use the estimate" in err
