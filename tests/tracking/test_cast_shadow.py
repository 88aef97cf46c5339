"""The cast-shadow rule of the real footage's truth (tests/cases/cast_shadow.py): on a
synthetic street, a figure with a soft shadow at its feet, masked as the truth maker masks
it (some channel off the empty street by over 35 grey levels), loses the shadow and keeps
all of itself: its dark legs' blurred rim, grey shoes, light warm shoes, and a grey patch on
its body that is as dark as the shadow."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from tests.cases.cast_shadow import CHROMA, RATIO, cast_shadow, without_cast_shadow

STREET = np.array([190.0, 188.0, 185.0])
BLACK = np.array([20.0, 20.0, 26.0])


def _scene(shoe=(90.0, 90.0, 92.0), patch=None, legs=BLACK, seed=0):
    """(frame, background, object, shadow core): a figure standing on a grey street, lit
    from above and behind, its shadow (the street at 0.7, a 2 px soft edge) on the ground
    between and behind its feet; the camera blurs everything by 0.7 px."""
    rng = np.random.default_rng(seed)
    h, w = 130, 110
    texture = ndimage.gaussian_filter(rng.normal(0, 1, (h, w)), 2)
    background = STREET + 20 * texture[..., None] / texture.std() * 0.3
    background += rng.normal(0, 2, (h, w, 1))
    obj = np.zeros((h, w), bool)
    colour = np.zeros((h, w, 3))
    body = (slice(10, 72), slice(40, 66))
    shins = ((slice(72, 104), slice(38, 46)), (slice(72, 104), slice(60, 68)))
    shoes = ((slice(104, 110), slice(30, 46)), (slice(104, 110), slice(60, 76)))
    obj[body] = True
    colour[body] = BLACK
    for part in shins:
        obj[part] = True
        colour[part] = legs
    for part in shoes:
        obj[part] = True
        colour[part] = shoe
    if patch is not None:  # a grey cloth on the chest, as dark as the shadow
        colour[25:40, 45:61] = patch
    core = np.zeros((h, w), bool)
    core[100:118, 26:84] = True
    shade = 1 - 0.3 * ndimage.gaussian_filter(core.astype(float), 2)
    lit = background * shade[..., None]
    frame = np.where(obj[..., None], colour, lit)
    frame = ndimage.gaussian_filter(frame, (0.7, 0.7, 0))
    frame += rng.normal(0, 2, frame.shape)
    return frame, background, obj, core & ~ndimage.binary_dilation(obj, iterations=2)


def _truth_mask(frame, background):
    """The old maker's mask: some channel off the street by over 35 grey levels."""
    mask = np.abs(frame - background).max(axis=-1) > 35
    return ndimage.binary_fill_holes(ndimage.binary_closing(mask, iterations=2))


def test_scene_is_what_it_says():
    """The preconditions the other tests lean on: the shadow is in the old mask, and
    the grey shoes are darker than a shadow."""
    frame, background, obj, shadow = _scene()
    mask = _truth_mask(frame, background)
    assert mask[shadow].mean() > 0.9  # the maker took the shadow for the figure
    assert mask[obj].mean() > 0.99
    ratio = frame.sum(-1) / background.sum(-1)
    assert np.median(ratio[shadow]) == pytest.approx(0.72, abs=0.03)


def test_shadow_leaves_the_mask_the_figure_stays():
    frame, background, obj, shadow = _scene()
    mask = _truth_mask(frame, background)
    new = without_cast_shadow(frame, background, mask)
    assert new[shadow & mask].mean() < 0.1
    assert new[obj].mean() > 0.99  # legs, shoes and their blurred rim kept
    assert not (new & ~mask).any()  # it only ever removes


def test_blurred_rim_of_dark_legs_is_not_shadow():
    """Next to the black legs the blur mixes black and street into a grey as dark as the
    shadow, of the street's colour: only the ratio's steep change tells it apart."""
    frame, background, obj, _ = _scene()
    mask = _truth_mask(frame, background)
    rim = mask & ~obj & ndimage.binary_dilation(obj, iterations=1)
    rim[:90] = False  # the ground band (rows 91-118) above the shadow
    rim[97:] = False
    a = (frame * background).sum(-1) / (background * background).sum(-1)
    in_band = rim & (a > RATIO[0]) & (a < RATIO[1])
    assert in_band.sum() > 20  # the colour tests alone would call these shadow
    assert not cast_shadow(frame, background, mask)[in_band].any()


def test_light_warm_shoes_are_not_shadow():
    """Light beige shoes (vtest's walker B) are as dark as a shadow and nearly of the street's
    colour; a shadow, lit by the sky alone, is never warmer than its ground."""
    shoe = np.array([152.0, 149.0, 132.0])
    frame, background, obj, shadow = _scene(shoe=shoe)
    a = shoe @ STREET / (STREET @ STREET)
    assert RATIO[0] < a < RATIO[1]
    assert np.linalg.norm(shoe - a * STREET) / np.linalg.norm(STREET) < CHROMA
    mask = _truth_mask(frame, background)
    new = without_cast_shadow(frame, background, mask)
    shoes = obj.copy()
    shoes[:104] = False
    assert new[shoes].mean() > 0.97
    assert new[shadow & mask].mean() < 0.1


def test_light_jeans_are_not_shadow():
    """Faded jeans over the shadow's ground are as dark as a shadow and flat inside, but
    blue on a grey street: not the street's colour."""
    jeans = np.array([110.0, 130.0, 175.0])
    a = jeans @ STREET / (STREET @ STREET)
    assert RATIO[0] < a < RATIO[1]
    frame, background, obj, shadow = _scene(legs=jeans)
    mask = _truth_mask(frame, background)
    new = without_cast_shadow(frame, background, mask)
    assert new[obj].mean() > 0.99
    assert new[shadow & mask].mean() < 0.1


def test_grey_patch_on_the_body_is_not_shadow():
    """A patch as dark as the shadow, of the street's colour and flat, high on the figure:
    shadows fall on the ground at the feet."""
    patch = STREET * 0.7
    frame, background, obj, _ = _scene(patch=patch)
    mask = _truth_mask(frame, background)
    new = without_cast_shadow(frame, background, mask)
    assert new[25:40, 45:61].all()


def test_empty_mask():
    frame, background, _, _ = _scene()
    empty = np.zeros(frame.shape[:2], bool)
    assert not cast_shadow(frame, background, empty).any()
    assert not without_cast_shadow(frame, background, empty).any()
