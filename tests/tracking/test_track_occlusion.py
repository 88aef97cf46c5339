"""Occlusion and reappearance (issue 35, motion='image'): the contour retreats where the
object is hidden, grows back where it reappears, and leaves no piece on the occluder."""

import numpy as np
import pytest
from test_track_image import H, W, _disc_frames, _iou

from clpde.tracking.occlusion import align, hidden_by_still, lost_part, visible_pieces
from clpde.tracking.tracker import track


def _disc(cy, cx, radius=9):
    yy, xx = np.mgrid[:H, :W]
    return np.hypot(yy - cy, xx - cx) < radius


@pytest.mark.parametrize(("width", "radius", "speed"), [(6, 9, 4), (12, 9, 4), (20, 7, 5)])
def test_disc_passes_behind_a_bar_and_out_again(width, radius, speed):
    # a textured disc moves through a bar (across it, or for the 20 px bar wholly hidden
    # for two frames) and out on the other side: once it is out, the contour is on it
    # again and nothing of it stays on the bar
    rng = np.random.default_rng(5)
    bar = np.zeros((H, W), bool)
    bar[:, 46 : 46 + width] = True
    centres = [(32, 20 + speed * t) for t in range(16)]
    frames, truth = _disc_frames(rng, centres, radius=radius, colour=True, occluder=bar)
    masks = track(frames, truth[0], progress=False)
    out = [t for t, (cy, cx) in enumerate(centres) if 46 + width < cx - radius < W - 2 * radius]
    assert len(out) >= 3
    for t in out:
        assert _iou(masks[t], truth[t]) >= 0.8
        assert not (masks[t] & bar).any()
    # while it passes, the contour keeps to its visible part (where a fair part shows)
    for t in range(1, len(masks)):
        assert (masks[t] & bar).sum() <= 0.1 * truth[0].sum()
        if truth[t].sum() >= 0.3 * truth[0].sum():
            assert _iou(masks[t], truth[t]) >= 0.6


def test_hidden_by_a_still_cut_not_by_a_shrink():
    # the cut through the object stays where last frame's outline was: hidden; the same
    # loss with the cut moved along with the object: the object shrank
    predicted = _disc(32, 44)
    bar = np.zeros((H, W), bool)
    bar[:, 46:52] = True
    previous = _disc(32, 40) & ~bar
    mask = predicted & ~bar
    lost = lost_part(predicted, mask)
    ratio = np.where(bar, 2.0, -2.0)
    assert hidden_by_still(lost, mask, previous, ratio, np.array([0.0, 4.0]))
    # a still object tells nothing; nor does a lost part that looks like the object
    assert not hidden_by_still(lost, mask, previous, ratio, np.array([0.0, 0.5]))
    assert not hidden_by_still(lost, mask, previous, -ratio, np.array([0.0, 4.0]))
    shrunk = _disc(32, 40) & (np.arange(W) < 42)[None, :]
    assert not hidden_by_still(lost, mask, shrunk, ratio, np.array([0.0, 4.0]))


def test_visible_pieces_drop_the_occluder_and_strays():
    whole = _disc(32, 44)
    bar = np.zeros((H, W), bool)
    bar[:, 46:52] = True
    mask = whole & ~bar  # the object on both sides of the bar
    stray = np.zeros((H, W), bool)
    stray[5:9, 80:84] = True  # off the whole shape
    on_bar = np.zeros((H, W), bool)
    on_bar[28:36, 46:49] = True  # a strip of the bar taken in with the object
    ratio = np.where(bar | stray, 2.0, -2.0)  # the bar and the stray look unlike the object
    kept = visible_pieces(mask | stray | on_bar, whole, ratio)
    assert (kept == mask).all()
    # without the appearance, pieces off the whole shape go, the rest stays
    assert (visible_pieces(mask | stray | on_bar, whole, None) == (mask | on_bar)).all()


def test_align_lays_the_whole_shape_on_the_visible_outline():
    whole = _disc(32, 44)
    mask = _disc(34, 46) & (np.arange(W) < 48)[None, :]
    lost = lost_part(np.roll(whole, (2, 2), (0, 1)), mask)
    assert align(whole, mask, lost).tolist() == [2.0, 2.0]
