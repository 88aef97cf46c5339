"""The object's motion where its mask took in still ground (issue 35's grey-14: the
affine fit took the still strip for a stretch, and the contour leaked further)."""

import numpy as np
import pytest
from scipy import ndimage

from clpde.tracking import appearance
from clpde.tracking.appearance import object_motion
from clpde.tracking.matched import matched_pixels

H, W = 80, 80


def _frames(seed, shift=(-4.0, 0.0)):
    """A graded, textured disc over a textured ground of its bottom's grey, moved by
    `shift`; the first frame's disc with a 6 px strip of the ground below it (a leak)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:H, :W] + 0.0
    ground = 0.3 + 0.1 * ndimage.gaussian_filter(rng.normal(size=(H, W)), 1.0) / 0.28
    skin = 0.03 * ndimage.gaussian_filter(rng.normal(size=(2 * H, 2 * W)), 1.0) / 0.28

    def frame(cy, cx):
        disc = np.hypot(yy - cy, xx - cx) < 14
        # the object's grade: bright at its top, the ground's grey at its bottom
        obj = (
            0.3 + 0.15 * (cy - yy) / 14 + skin[(yy - cy + H).astype(int), (xx - cx + W).astype(int)]
        )
        return np.where(disc, obj, ground) + rng.normal(0, 0.005, (H, W)), disc

    before, disc = frame(44.0, 40.0)
    after, _ = frame(44.0 + shift[0], 40.0 + shift[1])
    leak = disc | ((yy >= 44) & (yy < 64) & (np.abs(xx - 40) < 10))
    return before, after, leak


def _stretch(a):
    return float(np.abs(np.linalg.svd(a[:, :2], compute_uv=False) - 1).max())


@pytest.mark.parametrize("seed", range(3))
def test_still_ground_in_the_mask_is_no_stretch(seed):
    before, after, leak = _frames(seed)
    a = object_motion(before[None], after[None], leak)
    assert _stretch(a) < 0.05
    centre = np.array(ndimage.center_of_mass(leak))
    moved = np.linalg.solve(a[:, :2], centre - a[:, 2]) - centre
    assert np.abs(moved - [-4.0, 0.0]).max() < 0.5


def test_the_stretch_is_the_still_grounds(monkeypatch):
    # the fit on all of the mask's pixels: the still strip holds the object's bottom back
    monkeypatch.setattr(appearance, "MOVING", 0)
    stretches = [_stretch(object_motion(b[None], a[None], m)) for b, a, m in map(_frames, range(3))]
    assert min(stretches) > 0.08


def test_an_unreliable_appearance_leaves_out_only_what_clearly_looks_otherwise():
    # a graded object whose bottom the appearance mildly takes for the surroundings
    mask = np.zeros((20, 20), bool)
    mask[4:16, 4:16] = True
    ratio = np.full((20, 20), -0.3)  # mildly the object
    ratio[10:16] = 0.4  # mild: ambiguous bins
    ratio[15, 4:16] = 2.0  # clear: a strip of the ground
    believed = matched_pixels(mask, ratio, 0.5)
    assert believed.sum() == 6 * 12  # the mild preference decides
    unreliable = matched_pixels(mask, ratio, 0.0)
    assert unreliable.sum() == 11 * 12  # the clear strip alone is left out
    assert not unreliable[15].any()
    assert matched_pixels(mask, None, 0.0) is mask
