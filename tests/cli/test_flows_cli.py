"""The command line of the flows: denoise, diffuse, regions and surface, as a new user meets it."""

import numpy as np
import pytest
from PIL import Image

from clpde.cli import main


@pytest.fixture
def noisy_png(tmp_path):
    rng = np.random.default_rng(5)
    image = np.clip(
        128 + 40 * (np.arange(64)[None, :] > 32) + rng.normal(0, 12, (64, 64)), 0, 255
    ).astype(np.uint8)
    path = tmp_path / "noisy.png"
    Image.fromarray(image).save(path)
    return path


def test_denoise_prints_the_noise_level_it_estimated(noisy_png, tmp_path, capsys):
    assert main(["denoise", str(noisy_png), str(tmp_path / "out.png")]) == 0
    line = capsys.readouterr().err
    assert "noise sigma estimated" in line
    level = float(line.rsplit("estimated", 1)[1].split()[0].rstrip(","))
    assert 8 < level < 16  # the noise added was 12 grey levels


def test_denoise_with_weight_prints_no_noise_level(noisy_png, tmp_path, capsys):
    assert main(["denoise", str(noisy_png), str(tmp_path / "out.png"), "--weight", "0.1"]) == 0
    assert "noise sigma" not in capsys.readouterr().err


def test_diffuse_presmooth_matches_the_library(noisy_png, tmp_path):
    import clpde
    from clpde.io import read_image

    out = tmp_path / "pm.png"
    assert (
        main(
            [
                "diffuse",
                str(noisy_png),
                str(out),
                "--flow",
                "perona-malik",
                "--steps",
                "20",
                "--presmooth",
                "1.5",
            ]
        )
        == 0
    )
    want = clpde.diffuse(read_image(noisy_png), "perona-malik", steps=20, presmooth=1.5)
    np.testing.assert_array_equal(read_image(out), want)
    assert main(["diffuse", str(noisy_png), str(out), "--flow", "heat", "--presmooth", "1"]) == 2


def test_denoise_per_channel_option(tmp_path, capsys):
    import clpde
    from clpde.io import read_image

    rgb = np.random.default_rng(2).integers(0, 255, (24, 28, 3), dtype=np.uint8)
    Image.fromarray(rgb).save(tmp_path / "in.png")
    for flag, vectorial in (([], True), (["--per-channel"], False)):
        out = tmp_path / f"out{len(flag)}.png"
        assert main(["denoise", str(tmp_path / "in.png"), str(out), "--weight", "0.1", *flag]) == 0
        want = clpde.denoise_tv(rgb, weight=0.1, channel_axis=-1, vectorial=vectorial)
        np.testing.assert_array_equal(read_image(out), want)
