"""motion='checked' (issue 35): the Kalman filter's shift checked against a wide search of
the image, so that an object moving faster than the filter's search radius is followed
from the first frame."""

import numpy as np
import pytest
from scipy import ndimage

from clpde.cli import main
from clpde.tracking.motion_filter import MotionFilter, local_contrast
from clpde.tracking.prediction import checked_shift
from clpde.tracking.tracker import track

H, W = 80, 176


def _iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def _fast_disc(step=20, frames=7, seed=0):
    """A bright disc moving `step` px a frame to the right over a textured ground."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:H, :W]
    ground = 0.4 + 0.4 * ndimage.gaussian_filter(rng.normal(size=(H, W)), 2)
    images, truth = [], []
    for k in range(frames):
        disc = np.hypot(yy - 40, xx - 24 - step * k) < 12
        images.append(np.clip(np.where(disc, 0.75, ground) + rng.normal(0, 0.02, (H, W)), 0, 1))
        truth.append(disc)
    return np.array(images), np.array(truth)


def test_a_disc_moving_20px_a_frame_is_lost_by_kalman_and_kept_by_checked():
    frames, truth = _fast_disc()
    kalman = track(frames, truth[0], motion="kalman", progress=False)
    checked = track(frames, truth[0], motion="checked", progress=False)
    # the filter searches 6 px around a velocity that starts at 0: lost from frame 2 on
    assert max(_iou(a, b) for a, b in zip(kalman[2:], truth[2:], strict=True)) < 0.3
    assert min(_iou(a, b) for a, b in zip(checked[1:], truth[1:], strict=True)) > 0.9


def test_checked_shift_overrules_a_wrong_shift_and_keeps_a_right_one():
    frames, truth = _fast_disc()
    prev, cur = (local_contrast(f[None]) for f in frames[:2])
    shift, jumped = checked_shift(prev, cur, truth[0], (0.0, 3.0))
    assert jumped and abs(shift[0]) < 0.5 and abs(shift[1] - 20) < 0.5
    shift, jumped = checked_shift(prev, cur, truth[0], (0.0, 20.0))
    assert not jumped and shift == (0.0, 20.0)
    # nothing to match: the filter's shift stands
    assert checked_shift(prev, cur, np.zeros((H, W), bool), (1.0, 2.0)) == ((1.0, 2.0), False)


def test_a_jump_restarts_the_filter_at_the_checked_shift():
    f = MotionFilter("kalman")
    f.jump((2.0, 20.0))
    assert f.v.tolist() == [2.0, 20.0] and f.measured.tolist() == [2.0, 20.0]


@pytest.mark.parametrize("motion", ["checked", "wrong"])
def test_the_command_line_takes_motion_checked(tmp_path, motion, capsys):
    import imageio.v3 as iio
    import tifffile

    frames, truth = _fast_disc(frames=3)
    stack, mask = tmp_path / "stack.tif", tmp_path / "mask.png"
    tifffile.imwrite(stack, (frames * 255).astype(np.uint8), photometric="minisblack")
    iio.imwrite(mask, truth[0].astype(np.uint8) * 255)
    out = tmp_path / "out"
    args = ["track", str(stack), "--init", str(mask), "-o", str(out), "--no-gif"]
    code = main(args + ["--motion", motion])
    if motion == "wrong":
        assert code == 2 and "--motion" in capsys.readouterr().err
    else:
        assert code == 0 and _iou(iio.imread(out / "mask_0002.png") > 0, truth[2]) > 0.9
