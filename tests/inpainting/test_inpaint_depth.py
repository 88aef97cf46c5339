"""Piecewise-smooth surrounds (clpde/inpainting/depth.py) and the rendered disparity maps
that widen the corpus's calibration half (tests/cases/inpaint_depth.py)."""

import numpy as np
from scipy import ndimage

import clpde
from clpde.inpainting import depth, pick
from tests.cases import inpaint_corpus, inpaint_depth


def _case(name):
    return next(c for c in inpaint_depth.build() if c.name == name)


def test_a_depth_map_is_told_from_smooth_fields_and_fractals():
    ok = np.ones((72, 72), bool)
    disparity = inpaint_depth.scene(1)[20:92, 20:92].astype(float)
    assert depth.flat_share(disparity, ok) >= depth.FLAT_SHARE
    assert depth.jump(disparity, ok) >= depth.JUMP
    # a smooth field is as flat, but has no jump: the smooth route keeps it
    field = ndimage.gaussian_filter(np.random.default_rng(5).standard_normal((112, 112)), 20)
    assert depth.flat_share(field[:72, :72], ok) >= depth.FLAT_SHARE
    assert depth.jump(field[:72, :72], ok) < 0.5 * depth.JUMP
    fractal = inpaint_corpus.fractal(0)[:72, :72]
    assert depth.flat_share(fractal, ok) < 0.2
    # a hole's pixels are not read
    holed = disparity.copy()
    holed[30:40, 30:40] = 1e9
    hole = np.zeros_like(ok)
    hole[30:40, 30:40] = True
    assert depth.flat_share(holed, ~hole) == depth.flat_share(disparity, ~hole)


def test_a_depth_map_s_voids_keep_the_spectral_fill(monkeypatch):
    case = _case("scene-uint16-4/voids")
    image, mask = case.damaged(), case.mask
    planes = np.where(mask, 0.0, image.astype(float))[None]
    parts = pick.clusters_of(mask)
    none = np.zeros_like(mask)

    def run(**kw):
        return clpde.inpaint(image, mask, progress=False, seed=0, **kw)

    assert pick.smooth_clusters(planes, mask, parts, none).size == 0
    default, spectral = run(), run(method="spectral")
    assert np.array_equal(default, spectral)
    # without the test the smooth route takes two of its voids, and loses 2.6 dB
    monkeypatch.setattr(depth, "FLAT_SHARE", 2.0)
    assert pick.smooth_clusters(planes, mask, parts, none).size == 2
    routed = run()
    assert not np.array_equal(routed, spectral)
    assert inpaint_corpus.psnr(case, default) > inpaint_corpus.psnr(case, routed) + 1.0


def test_the_rendered_maps_are_calibration_cases_of_their_own_sources():
    cases = inpaint_depth.build()
    assert {c.half for c in cases} == {"calibration"}
    assert {c.damage for c in cases} == {"voids", "blobs"}
    assert {c.kind for c in cases} == {"float", "uint16"}
    corpus_sources = {c.source for c in inpaint_corpus.build()}
    assert not {c.source for c in cases} & corpus_sources
    again = inpaint_depth.build()
    for a, b in zip(cases, again, strict=True):
        assert a.name == b.name and np.array_equal(a.mask, b.mask)
        assert np.array_equal(a.truth, b.truth)
    # piecewise planar: most pixels' Laplacian vanishes, the outlines jump
    for c in cases:
        t = c.truth.astype(float)
        ok = np.ones(t.shape, bool)
        assert depth.flat_share(t, ok) > 0.8 and depth.jump(t, ok) > 1.0, c.name
        assert 0.02 < c.mask.mean() < 0.2, c.name
