"""Level-set kernels against their numpy references, and reinitialisation's mathematics."""

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.fields import Field, Grid, index_list
from clpde.tracking.levelset import LevelSet, signed_distance
from tests.reference import levelset as ref


def _field(grid, values):
    return Field.from_host(grid, np.asarray(values)[np.newaxis])


def _padded(field):
    return field.data.get()[0].astype(np.float64)


def _circle_sdf(n, r, cx=None, cy=None):
    cx = n / 2 - 0.3 if cx is None else cx
    cy = n / 2 + 0.2 if cy is None else cy
    y, x = np.mgrid[:n, :n]
    return np.hypot(x - cx, y - cy) - r


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_reinit_step_matches_reference_on_grid_and_list(runtime, rng, kind):
    n = 24
    if kind == "random":
        phi = rng.normal(size=(n, n)) * 3
    else:
        phi = _circle_sdf(n, 7) * (1 + 0.5 * rng.random((n, n)))
    grid = Grid(runtime, n, n, 1, 2, np.dtype(np.float32))
    p, p0 = _field(grid, phi), _field(grid, phi * 1.3)
    want = ref.reinit_step(_padded(p), _padded(p0), 0.5)
    out = p.copy()
    grid.launch(
        grid.kernel("tracking/levelset.cl", "levelset_reinit_step"),
        p.data.data,
        p0.data.data,
        out.data.data,
        grid.scalar(0.5),
    )
    np.testing.assert_allclose(out.to_host()[0], want, atol=2e-5, rtol=1e-5)

    chosen = rng.random((n, n)) < 0.3
    cells = index_list(grid, chosen)
    out = p.copy()
    grid.launch_list(
        grid.kernel("tracking/levelset.cl", "levelset_reinit_step_list"),
        cells,
        p.data.data,
        p0.data.data,
        out.data.data,
        grid.scalar(0.5),
        np.int32(grid.sx),
    )
    np.testing.assert_allclose(out.to_host()[0], np.where(chosen, want, phi), atol=2e-5, rtol=1e-5)


def test_mark_band_and_gradient_magnitude_match_reference(runtime, rng):
    u = rng.normal(size=(17, 23)) * 4
    grid = Grid(runtime, 23, 17, 1, 2, np.dtype(np.float32))
    ls = LevelSet(runtime, u, band_width=3.0)
    padded = ls.band_mask.get()
    on_grid = np.pad(u, 2, mode="edge").astype(np.float32)  # the level set's frozen margin
    want = ref.mark_band(on_grid, 3.0, margin=2)
    np.testing.assert_array_equal(padded[2:-2, 2:-2], want)
    assert not padded[:4].any() and not padded[:, :4].any()  # ghosts and margin stay out
    assert ls.band.n == int((want > 0).sum()) == int(ls.band_cells().sum())

    img = rng.random((17, 23))
    f = _field(grid, img)
    out = f.copy()
    grid.launch(
        grid.kernel("tracking/levelset.cl", "levelset_gradient_magnitude"),
        f.data.data,
        out.data.data,
    )
    np.testing.assert_allclose(out.to_host()[0], ref.gradient_magnitude(_padded(f)), atol=1e-6)


def test_upwind_norm_is_second_order_on_a_smooth_field():
    # The slope-limited norm of a smooth distance field is exact to O(h^2) away from kinks.
    errors = []
    for n in (32, 64):
        h = 1.0 / n
        y, x = (np.mgrid[:n, :n] + 0.5) * h
        u = np.hypot(x + 0.7, y + 0.4) / h  # grid units: |grad u| = 1 exactly
        p = ref.pad(u)
        errors.append(np.abs(ref.upwind_norm(p, 1.0) - 1)[4:-4, 4:-4].max())
    assert errors[1] < errors[0] / 3


def test_signed_distance_gives_the_mask_back_and_rejects_bad_masks(rng):
    mask = rng.random((20, 30)) < 0.4
    sd = signed_distance(mask)
    np.testing.assert_array_equal(sd < 0, mask)
    np.testing.assert_allclose(sd, ref.signed_distance(mask))
    with pytest.raises(InputError, match="empty"):
        signed_distance(np.zeros((5, 5), bool))
    with pytest.raises(InputError, match="whole image"):
        signed_distance(np.ones((5, 5), bool))


def _crossings(u):
    """Sub-pixel positions of the zero level set on grid edges (linear interpolation)."""
    points = []
    for axis in (0, 1):
        a = u if axis == 1 else u.T
        left, right = a[:, :-1], a[:, 1:]
        rows, cols = np.nonzero(left * right < 0)
        t = left[rows, cols] / (left[rows, cols] - right[rows, cols])
        pos = np.stack([rows, cols + t], axis=1)
        points.append(pos if axis == 1 else pos[:, ::-1])
    return np.concatenate(points)


@pytest.mark.parametrize("distortion", ["stretched", "bumpy"])
def test_reinitialisation_restores_unit_gradient_and_keeps_the_front(runtime, distortion):
    n, r = 64, 17.3
    y, x = np.mgrid[:n, :n]
    cx, cy = 31.6, 32.3
    true = np.hypot(x - cx, y - cy) - r
    if distortion == "stretched":
        u0 = true * (1 + x / n) * 2.5  # far from unit gradient, same front
    else:
        u0 = true * (1.5 + np.sin(x / 3.0) * np.cos(y / 4.0))
    ls = LevelSet(runtime, u0, band_width=3.0)
    ls.reinitialize(iterations=40)
    u = ls.values()
    band = np.abs(true) < 3
    gy, gx = np.gradient(u)
    grad_error = np.abs(np.hypot(gx, gy) - 1)[band]
    assert np.median(grad_error) < 0.03 and grad_error.mean() < 0.06
    # The front: the crossing points of u0 and of u, each measured against the circle.
    moved = np.abs(np.hypot(*(_crossings(u) - [cy, cx]).T) - r)
    before = np.abs(np.hypot(*(_crossings(u0) - [cy, cx]).T) - r)
    assert moved.max() < 0.1 and moved.max() < before.max() + 0.05
    assert np.abs(u - true)[band].mean() < 0.05


def test_dilate_band_matches_reference(runtime, rng):
    u = rng.normal(size=(19, 25)) * 5
    ls = LevelSet(runtime, u, band_width=3.0)
    ls.dilate_band()
    band = ls.band_mask.get()[2:-2, 2:-2]
    want = ref.dilate_band(band, 3, 2)
    np.testing.assert_array_equal(ls._near_mask.get()[2:-2, 2:-2], want)
    assert want.sum() > band.astype(bool).sum()


def test_plain_reinit_matches_reference_and_the_subcell_fix_is_more_accurate(runtime, rng):
    n = 24
    phi = _circle_sdf(n, 7) * (1 + 0.5 * rng.random((n, n)))
    grid = Grid(runtime, n, n, 1, 2, np.dtype(np.float32))
    p, p0 = _field(grid, phi), _field(grid, phi * 1.3)
    out = p.copy()
    cells = index_list(grid, np.ones((n, n), bool))
    grid.launch_list(
        grid.kernel("tracking/levelset.cl", "levelset_reinit_step_list", PLAIN_REINIT=1),
        cells,
        p.data.data,
        p0.data.data,
        out.data.data,
        grid.scalar(0.5),
        np.int32(grid.sx),
    )
    want = ref.reinit_step(_padded(p), _padded(p0), 0.5, subcell_fix=False)
    np.testing.assert_allclose(out.to_host()[0], want, atol=2e-5, rtol=1e-5)

    m, r = 64, 17.3
    y, x = np.mgrid[:m, :m]
    true = np.hypot(x - 31.6, y - 32.3) - r
    band = np.abs(true) < 3
    for u0 in (true * (1 + x / m) * 2.5, true * (1.5 + np.sin(x / 3.0) * np.cos(y / 4.0))):
        errors = []
        for fix in (True, False):
            ls = LevelSet(runtime, u0)
            ls.reinitialize(40, subcell_fix=fix)
            errors.append(np.abs(ls.values() - true)[band].mean())
        assert errors[0] * 3 < errors[1], errors
