"""Blotch recall on real footage (opencv-doc's vtest.avi: people walking past a static
camera): a blotch the detector confirms is taken whole, its soft rim and the inside where
it disturbs the flows included, and a large one is not mistaken for a motion boundary;
the walking people are still never taken for dirt."""

import numpy as np
import pytest
from scipy import ndimage

import clpde
from clpde.film.stream import KEEP
from tests.cases.footage import VTEST
from tests.cases.footage import people as _people

cv2 = pytest.importorskip("cv2")
pytestmark = pytest.mark.skipif(not VTEST.exists(), reason="opencv-doc's vtest.avi is absent")


def _soft_blotch(frames, t, y, x, radius, value, soft):
    """frames with a soft-rimmed blotch (a disc blurred by a Gaussian of `soft` px, laid
    over frame t at `value`); its true pixels (opacity >= 0.2, changed by >= 6 levels, as
    benchmarks/film_corpus.py counts them) and every pixel it touches (opacity > 0.02)."""
    yy, xx = np.mgrid[0 : frames.shape[1], 0 : frames.shape[2]]
    a = ndimage.gaussian_filter((np.hypot(yy - y, xx - x) <= radius).astype(float), soft)
    dirty = frames.copy()
    new = frames[t] * (1 - a[..., None]) + a[..., None] * value
    dirty[t] = np.clip(np.rint(new), 0, 255).astype(np.uint8)
    changed = np.abs(dirty[t].astype(int) - frames[t].astype(int)).max(-1)
    return dirty, (a >= 0.2) & (changed >= 6), a > 0.02


def test_soft_rimmed_blotch_is_taken_whole_and_no_further():
    """A bright blotch with a soft rim on a middle frame, beside the walking people: its
    rim and the inside where it disturbs the flows are taken too (the first pass alone
    found 77% of its true pixels), and next to nothing (2% of its true pixels) is taken
    more than 2 px beyond what it touches: the growth is bounded and stays on it."""
    clean = _people()
    dirty, truth, touched = _soft_blotch(clean, 4, 60, 110, 7, 230, 1.5)
    kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)[1]
    assert (kinds[4][truth] == 1).mean() >= 0.95
    near = ndimage.binary_dilation(touched, iterations=2)
    assert (kinds[4][~near] == 1).sum() <= 0.02 * truth.sum()


def test_large_blotch_is_not_taken_for_a_motion_boundary():
    """A large dark blotch (radius 10 px) disturbs the flows from its frame to both
    neighbours, which then spread around it as at a motion boundary: the flow between the
    neighbours, which carry none of it, shows no boundary there, and the blotch is found
    (the ring check refused all of it before)."""
    clean = _people()
    dirty, truth, _ = _soft_blotch(clean, 4, 55, 100, 10, 15, 1.5)
    kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)[1]
    assert (kinds[4][truth] == 1).mean() >= 0.9


def test_walking_people_are_still_not_dirt():
    """With blotches in the film (so that every stage runs, the growth included), no pixel
    of the walking people is called damage in the frames without a blotch, next to nothing
    (2% of the blotch's true pixels) beyond 2 px of what a blotch touches in the others,
    and outside what the blotches touch at most 0.5% of any frame changes by more than 10
    levels, the ends included."""
    clean = _people()
    dirty, truth4, touched4 = _soft_blotch(clean, 4, 60, 110, 7, 230, 1.5)
    dirty, truth2, touched2 = _soft_blotch(dirty, 2, 50, 60, 6, 10, 1.0)
    touched = np.zeros(clean.shape[:3], bool)
    touched[4], touched[2] = touched4, touched2
    mask, kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)
    near = np.stack([ndimage.binary_dilation(m, iterations=2) for m in touched])
    assert not mask[[1, 3, 5, 6]].any()
    for t, truth in ((2, truth2), (4, truth4)):
        assert (mask[t] & ~near[t]).sum() <= 0.02 * truth.sum()
    out = clpde.inpaint_video(dirty, mask, channel_axis=-1, keep=KEEP)
    changed = np.abs(out.astype(int) - dirty.astype(int)).max(-1) > 10
    assert (changed & ~near).mean(axis=(1, 2)).max() <= 0.005


def _grained(frames, level=3.0, seed=1):
    """frames with fresh film grain each frame (slightly blurred Gaussian of `level` grey
    levels, as benchmarks/film_corpus.py draws it)."""
    rng = np.random.default_rng(seed)
    grain = np.stack(
        [ndimage.gaussian_filter(rng.standard_normal(frames.shape[1:3]), 0.6) for _ in frames]
    )
    grain *= level / grain.std()
    return np.clip(np.rint(frames + grain[..., None]), 0, 255).astype(np.uint8)


def test_faint_soft_rimmed_blotch_under_grain_is_found():
    """A faint dark blotch (20 levels under its surroundings' median, a soft rim of 1 px)
    on a middle frame of grained footage: each of its pixels is within 2-5 grain deviations,
    but its square's mean stands out; its pixels carry that mean, so they join one region
    (the pixels' own low level left it in pieces: 37% found), and the people walking past
    are still never dirt in the other frames."""
    clean = _grained(_people())
    yy, xx = np.mgrid[0 : clean.shape[1], 0 : clean.shape[2]]
    local = float(np.median(clean[4][np.hypot(yy - 60, xx - 110) <= 6]))
    dirty, truth, _ = _soft_blotch(clean, 4, 60, 110, 6, local - 20, 1.0)
    kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)[1]
    assert (kinds[4][truth] == 1).mean() >= 0.5
    assert not (kinds[[1, 2, 3, 5, 6]] == 1).any()
