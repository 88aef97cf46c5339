"""Whole faint blotches on a textured scene (clpde.film._whole): a flat patch a little off
its surroundings' median, on grained real footage (opencv-doc's vtest.avi), which the first
pass left out entirely, is found by its mean and by the scene detail it hides; the people
walking past are still not dirt. And the detail test itself: a region that hides its
neighbours' detail passes, one that keeps it (a flow error misplaces detail) does not."""

import numpy as np
import pytest
from scipy import ndimage

import clpde
from clpde.film._whole import HIDDEN, hides_detail
from tests.cases.footage import VTEST
from tests.film.test_film_recall import _grained, _people, _soft_blotch

pytest.importorskip("cv2")


@pytest.mark.skipif(not VTEST.exists(), reason="opencv-doc's vtest.avi is absent")
def test_faint_flat_blotch_on_texture_is_found_whole():
    """A bright blotch 15 levels over the median of a textured patch (radius 8 px, a soft
    rim of 1 px) on a middle frame: the first pass found none of it (its low-level pieces
    did not reach the threshold as regions); now most of it, next to nothing beyond 2 px
    of what it touches, and no blotch in the frames without one."""
    clean = _grained(_people())
    yy, xx = np.mgrid[0 : clean.shape[1], 0 : clean.shape[2]]
    local = float(np.median(clean[4][np.hypot(yy - 20, xx - 108) <= 8]))
    dirty, truth, touched = _soft_blotch(clean, 4, 20, 108, 8, local + 15, 1.0)
    kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)[1]
    assert (kinds[4][truth] == 1).mean() >= 0.5
    near = ndimage.binary_dilation(touched, iterations=2)
    assert (kinds[4][~near] == 1).sum() <= 0.02 * truth.sum()
    assert not (kinds[[1, 2, 3, 5, 6]] == 1).any()


def test_hides_detail_keeps_flat_regions_over_texture_only():
    """Two square regions of a frame: one flat (dirt over the scene), one carrying the same
    texture as the neighbours, shifted by a pixel (a flow error): only the flat one hides
    the detail; against neighbours without detail neither does."""
    rng = np.random.default_rng(3)
    scene = ndimage.gaussian_filter(rng.standard_normal((40, 60)), 0.8).astype(np.float32)
    frame = np.roll(scene, 1, axis=1)  # detail misplaced, not hidden
    frame[10:20, 10:20] = float(scene[10:20, 10:20].mean())  # detail hidden
    flat = np.zeros_like(scene)
    mask = np.zeros(scene.shape, bool)
    mask[10:20, 10:20] = mask[10:20, 35:45] = True
    inside = np.ones(scene.shape, bool)
    kept = hides_detail(frame, [(scene, inside, 1.0), (scene, inside, 1.0)], mask)
    assert kept[10:20, 10:20].all() and not kept[10:20, 35:45].any()
    # against neighbours without detail, nothing is hidden: not the flat region either
    kept = hides_detail(frame, [(flat, inside, 1.0)], mask)
    assert not kept.any()
    assert 0 < HIDDEN < 1
