"""A part's turn and shift, three parameters (issue 35, trackfoot: clpde/tracking/rigid.py,
used by turns.py beside the affine fit): a textured part turned about a point off its
centre and moved is fitted within half a pixel on its pixels; a part that only moved is
given no turn."""

import numpy as np
import pytest
from scipy import ndimage

from clpde.tracking.appearance import inverse
from clpde.tracking.rigid import rigid_fit

H, W = 90, 90


def _map(degrees, shift, about):
    """cur -> prev coordinates: prev's pixels turned by `degrees` about `about`, then moved
    by `shift`."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    back = np.array([[c, -s], [s, c]]).T
    return np.column_stack([back, about - back @ (np.asarray(shift) + about)])


def _scene(seed, degrees, shift):
    rng = np.random.default_rng(seed)
    prev = ndimage.gaussian_filter(rng.random((H, W)), 1.2)
    prev = (prev - prev.min()) / (prev.max() - prev.min())
    a = _map(degrees, shift, np.array([30.0, 45.0]))
    cur = ndimage.affine_transform(prev, a[:, :2], a[:, 2], order=3, mode="nearest")
    part = np.zeros((H, W), bool)
    part[30:55, 37:53] = True  # a leg below the knee (30, 45)
    return prev[None], cur[None], part, a


def _off(a, b, part):
    pts = np.array(np.nonzero(part), np.float64)
    ia, ib = inverse(a), inverse(b)
    pa = np.tensordot(ia[:, :2], pts, 1) + ia[:, 2:]
    pb = np.tensordot(ib[:, :2], pts, 1) + ib[:, 2:]
    return float(np.abs(pa - pb).max())


@pytest.mark.parametrize("seed", range(3))
def test_a_turned_part_is_fitted(seed):
    prev, cur, part, truth = _scene(seed, 12.0, (2.0, 3.0))
    # from the whole-pixel shift of the part's centre
    centre = np.array(ndimage.center_of_mass(part))
    d = np.rint(np.linalg.solve(truth[:, :2], centre - truth[:, 2]) - centre)
    fitted = rigid_fit(prev, cur, part, d, 6)
    assert _off(fitted, truth, part) < 0.5
    # the shift alone misses the turn by several px on the part's ends
    shifted = np.array([[1.0, 0.0, -d[0]], [0.0, 1.0, -d[1]]])
    assert _off(shifted, truth, part) > 2.0


def test_a_part_that_only_moved_gets_no_turn():
    prev, cur, part, truth = _scene(0, 0.0, (1.4, -2.3))
    fitted = rigid_fit(prev, cur, part, np.array([1.0, -2.0]), 6)
    assert _off(fitted, truth, part) < 0.2
    assert np.abs(fitted[:, :2] - np.eye(2)).max() < 0.01
