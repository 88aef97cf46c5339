"""The adaptive discrepancy's region term on the device (kernels/tracking/region.cl through
clpde.tracking.region_term.RegionTerm) against its numpy reference, step by step, and the
reference against scipy's filters and the term's purpose."""

import numpy as np
import pytest
from scipy import ndimage

from clpde.tracking.adaptive import noise_variance, region_features
from clpde.tracking.levelset import MARGIN, LevelSet, signed_distance
from clpde.tracking.region_term import RegionTerm, gaussian_weights
from tests.reference import track_region as rref


def _scene(rng, ny, nx, channels=1):
    y, x = np.mgrid[:ny, :nx]
    obj = np.hypot(y - ny / 2, (x - nx / 2) / 1.3) < min(ny, nx) / 4
    img = np.array([0.3 + (0.25 + 0.1 * c) * obj for c in range(channels)])
    img += 0.05 * rng.normal(size=img.shape)
    start = np.hypot(y - ny / 2 - 1, (x - nx / 2 - 2) / 1.3) < min(ny, nx) / 4
    return img, start


@pytest.mark.parametrize("sigma", [1.5, 3.0])
def test_reference_blur_is_scipys_gaussian_filter(rng, sigma):
    a = rng.normal(size=(2, 13, 18))
    w = rref.gaussian_weights(sigma, 3.0)
    assert np.allclose(w, gaussian_weights(sigma, 3.0), rtol=1e-15)
    want = np.array([ndimage.gaussian_filter(p, sigma, mode="nearest", truncate=3.0) for p in a])
    assert np.allclose(rref.blur2d(a, w), want, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize(
    "shape,channels,dtype,tol",
    [
        ((37, 29), 1, np.float32, 2e-4),
        ((24, 32), 3, np.float32, 2e-4),
        ((31, 26), 1, np.float64, 1e-10),
    ],
)
def test_region_term_kernels_match_reference(runtime, rng, shape, channels, dtype, tol):
    img, start = _scene(rng, *shape, channels)
    ls = LevelSet(runtime, signed_distance(start), 3.0, dtype)
    noise2 = 0.0025
    term = RegionTerm(ls, weight=0.8)
    term.start(ls, img, noise2)
    feats = region_features(img)
    inside = ls.values() < 0
    assert (inside == start).all()
    # region_moments and the coarse blur
    stats = term._stats.get().astype(np.float64)
    want = rref.blur2d(rref.moments(inside, feats), rref.gaussian_weights(3.0, 3.0))
    assert stats.shape == want.shape == (2 + 4 * len(feats), -(-shape[0] // 2), -(-shape[1] // 2))
    assert np.allclose(stats, want, rtol=tol, atol=tol)
    # region_llr and the pooling, from the device's statistics
    total, weight = rref.llr(stats, feats.astype(dtype).astype(np.float64), noise2, 0.5)
    assert np.allclose(term._w.get(), weight, rtol=tol, atol=tol)
    pooled = rref.blur2d(total[np.newaxis], rref.gaussian_weights(1.5, 4.0))[0]
    scale = np.abs(pooled).max()
    assert np.allclose(term._llr.get(), pooled, rtol=tol, atol=tol * scale)
    # region_speed on the level set's grid: the frame inside an edge-replicated margin
    field = ls.grid.interior(term.field.data.get())[0]
    want = np.pad(rref.speed(pooled, weight, 0.8), MARGIN, mode="edge")
    assert np.allclose(field, want, rtol=tol, atol=tol * 10)
    # and the chain as a whole
    whole = rref.region_speed(inside, feats, noise2, scale=0.8)
    assert np.allclose(field[MARGIN:-MARGIN, MARGIN:-MARGIN], whole, atol=10 * tol)


def test_region_term_follows_the_level_set_on_the_device(runtime, rng):
    img, start = _scene(rng, 40, 44)
    ls = LevelSet(runtime, signed_distance(start), 3.0, np.float64)
    term = RegionTerm(ls, weight=1.0)
    term.start(ls, img, 0.0025)
    before = term.field.data.get().copy()
    moved = np.roll(start, 3, axis=1)
    ls.assign(signed_distance(moved))
    term.update(ls)
    field = ls.grid.interior(term.field.data.get())[0][MARGIN:-MARGIN, MARGIN:-MARGIN]
    assert not np.array_equal(before, term.field.data.get())
    assert np.allclose(field, rref.region_speed(moved, region_features(img), 0.0025), atol=1e-10)


def test_region_term_of_weight_zero_is_zero(runtime, rng):
    img, start = _scene(rng, 20, 20)
    ls = LevelSet(runtime, signed_distance(start), 3.0, np.float32)
    term = RegionTerm(ls, weight=0.0)
    term.start(ls, img, 0.0025)
    assert not term.follows
    assert not term.field.data.get().any()


def test_region_term_points_the_contour_to_the_object(runtime, rng):
    y, x = np.mgrid[:60, :60]
    obj = np.hypot(y - 30, x - 30) < 12
    img = (0.3 + 0.3 * obj + rng.normal(0, 0.05, obj.shape))[np.newaxis]
    start = np.hypot(y - 30, x - 32) < 12  # 2 px off
    ls = LevelSet(runtime, signed_distance(start), 3.0, np.float32)
    term = RegionTerm(ls, weight=1.0)
    term.start(ls, img, noise_variance(img))
    speed = ls.grid.interior(term.field.data.get())[0][MARGIN:-MARGIN, MARGIN:-MARGIN]
    ring = np.abs(np.hypot(y - 30, x - 30) - 12) < 3
    truth = np.where(obj, -1, 1)  # inside: grow (negative), outside: shrink
    assert (np.sign(speed) == truth)[ring].mean() > 0.85
    assert np.abs(speed).max() <= 1
