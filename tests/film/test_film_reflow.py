"""The second look at a frame's blotches (clpde.film._reflow, issue 34): a blotch drags its
frame's flow around it; the flow there is mended from its surroundings, the windows stay
around the blotches, and the second look changes nothing in a frame without one."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

import clpde
from clpde.film import _reflow as reflow
from clpde.film import detect as fdet

cv2 = pytest.importorskip("cv2")


def _scene(ny=72, nx=96, seed=0):
    s = gaussian_filter(np.random.default_rng(seed).random((ny + 20, nx + 20)), 2.0)
    return (0.2 + 0.6 * (s - s.min()) / (s.max() - s.min())).astype(np.float32)


def test_windows_hold_the_blotches_with_their_reach():
    blotch = np.zeros((72, 96), bool)
    blotch[30:36, 40:46] = True
    blotch[2:4, 90:92] = True  # by the frame's corner: the window is cut by the frame
    wins = reflow.windows(blotch)
    assert len(wins) == 2
    for inner, crop in wins:
        for i, c, size in zip(inner, crop, blotch.shape, strict=True):
            assert 0 <= c.start <= i.start < i.stop <= c.stop <= size
        assert blotch[inner].any()
    got = np.zeros_like(blotch)
    for inner, _ in wins:
        got[inner] = True
    assert got[fdet.dilate(blotch, reflow.REACH)].all()


def test_mend_gives_the_dragged_flow_its_surroundings_values():
    """A pan of (-2, 1) px whose flow a blotch dragged to (0, 0) within 3 px of it: mended,
    the flow is the pan's again there, and unchanged beyond DRAG px of the blotch."""
    flow = np.zeros((72, 96, 2), np.float32)
    flow[..., 0], flow[..., 1] = -2.0, 1.0
    flow[:, 60:, 0] = -5.0  # another motion, 12 px off the blotch
    blotch = np.zeros((72, 96), bool)
    blotch[30:38, 40:48] = True
    dragged = fdet.dilate(blotch, 3)
    first = flow.copy()
    first[dragged] = 0.0
    bad = fdet.dilate(blotch, reflow.DRAG)
    got = reflow.mend(first, reflow._nearest(bad))
    assert np.array_equal(got[dragged], flow[dragged])
    assert np.array_equal(got[~bad], first[~bad])


def test_no_blotch_no_second_look(monkeypatch):
    """A frame without blotches is never looked at again, and a film without any gives the
    first look's result."""
    calls = []
    real = fdet.look_again

    def spy(scores, t, blotch, *args):
        calls.append(t)
        return real(scores, t, blotch, *args)

    monkeypatch.setattr(fdet, "look_again", spy)
    s = _scene()
    frames = np.stack([s[10:82, 10 + k : 106 + k] for k in range(5)])
    frames[2, 30:38, 40:48] = 0.95
    clpde.detect_defects(frames)
    assert calls == [2]
