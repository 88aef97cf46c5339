"""The spatial test reads a region on its core (issue 34): a soft rim blends dirt into the
scene, so a large soft-rimmed blotch where the motion is not trusted lies outside its
ring's range by the bar on its core, not over all its pixels (clpde.film._regions
._spatially_damage); the walking people stay clean."""

import numpy as np
import pytest
from scipy import ndimage

import clpde
from clpde.film._motion import FilmMotion
from tests.cases.footage import VTEST
from tests.cases.footage import people as _people
from tests.film.test_film_recall import _grained, _soft_blotch

cv2 = pytest.importorskip("cv2")
pytestmark = pytest.mark.skipif(not VTEST.exists(), reason="opencv-doc's vtest.avi is absent")


def _last_frame_not_trusted(monkeypatch, last):
    """No flow from the film's last frame is trusted (as where every forward-backward or
    loop check fails): its blotches go to the spatial path only."""
    trusted = FilmMotion.trusted

    def patched(self, t, k, partner, tol, fb):
        ok = trusted(self, t, k, partner, tol, fb)
        return np.zeros_like(ok) if t == last else ok

    monkeypatch.setattr(FilmMotion, "trusted", patched)


def test_soft_rimmed_blotch_at_the_end_where_motion_is_not_trusted_is_found(monkeypatch):
    """A dark blotch (radius 7 px, rim blurred by 2 px, 15 levels) on the last frame of
    grained walking people, no flow from that frame trusted: found (91% of its true
    pixels; none before the core rule, whose median over all its pixels fell short of the
    bar), nothing beyond 2 px of what it touches, nothing on the other frames."""
    clean = _grained(_people())
    last = len(clean) - 1
    _last_frame_not_trusted(monkeypatch, last)
    dirty, truth, touched = _soft_blotch(clean, last, 60, 110, 7, 15, 2.0)
    kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)[1]
    assert (kinds[last][truth] == 1).mean() >= 0.8
    near = ndimage.binary_dilation(touched, iterations=2)
    assert not (kinds[last][~near] == 1).any()
    assert not (kinds[:last] == 1).any()


def test_walking_people_untrusted_at_the_end_are_not_dirt(monkeypatch):
    """The same grained people with no damage and the same distrust: nothing is called
    damage on any frame (the people's soft edges and dark clothes are not dirt by their
    core), and the restoration changes no pixel."""
    clean = _grained(_people())
    _last_frame_not_trusted(monkeypatch, len(clean) - 1)
    mask = clpde.detect_defects(clean, channel_axis=-1)
    assert not mask.any()
    out = clpde.inpaint_video(clean, mask, channel_axis=-1)
    assert np.array_equal(out, clean)
