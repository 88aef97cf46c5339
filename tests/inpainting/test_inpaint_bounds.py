"""Fills stay within what surrounds them (clpde/inpainting/bounds.py): every method, every
dtype, each cluster of damage within the range of the known pixels around it; colours
inside the hull of the surroundings' colours (Navier-Stokes used to paint saturated
specks)."""

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import ConvexHull

import clpde
from clpde.inpainting import bounds

RING = bounds.RING


def _photo(size=48):
    from skimage import data

    return np.ascontiguousarray(data.astronaut()[200 : 200 + size, 250 : 250 + size])


def _text(shape):
    import cv2

    m = np.zeros(shape, np.uint8)
    for y in range(12, shape[0], 16):
        cv2.putText(m, "a1 x", (2, y), cv2.FONT_HERSHEY_SIMPLEX, 0.45, 1, 2, cv2.LINE_AA)
    m[30:42, 30:42] = 1  # and a blob
    return m > 0


def _rings(mask):
    """[(hole pixels, ring pixels)] per 8-connected cluster; the ring: every known pixel
    within RING of the cluster (a superset of bounds.py's, which gives each known pixel to
    its nearest cluster only)."""
    labels, n = ndimage.label(mask, np.ones((3, 3), bool))
    out = []
    for k in range(1, n + 1):
        comp = labels == k
        near = ndimage.distance_transform_edt(~comp) <= RING
        out.append((comp, near & ~mask))
    return out


def _inputs(kind, photo, mask):
    """(image to give, mask to give, known values in the given units) of one dtype."""
    f = photo.astype(np.float64) / 255
    if kind == "float01":
        return f.astype(np.float32), mask, f
    if kind == "nan":
        return np.where(mask[..., None], np.nan, f).astype(np.float32), None, f
    if kind == "uint16":
        return (photo.astype(np.uint16) * 257), mask, photo.astype(np.float64) * 257
    return photo, mask, photo.astype(np.float64)


@pytest.mark.parametrize("kind", ["float01", "nan", "uint8", "uint16"])
@pytest.mark.parametrize("method", [None, *clpde.inpainting.available()])
def test_fill_within_each_clusters_range(method, kind):
    photo = _photo()
    mask = _text(photo.shape[:2])
    image, given, known = _inputs(kind, photo, mask)
    options = {"max_steps": 200} if method == "transport" else {}
    out = clpde.inpaint(image, given, channel_axis=-1, method=method, seed=0, **options)
    out = np.asarray(out, np.float64)
    assert np.isfinite(out).all()
    for comp, ring in _rings(mask):
        lo, hi = known[ring].min(axis=0), known[ring].max(axis=0)
        fill = out[comp]
        assert (fill >= lo - 1e-6).all() and (fill <= hi + 1e-6).all(), (method, kind)


def test_soft_mask_fill_within_the_range_and_its_observed_value():
    """A half-damaged pixel is a blend of the fill and its observed value: its bound is the
    cluster's range widened to that value."""
    photo = _photo().astype(np.float32) / 255
    mask = _text(photo.shape[:2]).astype(np.float32)
    mask[mask > 0] = 0.5
    out = clpde.inpaint(photo, mask, channel_axis=-1)
    for comp, ring in _rings(mask > 0):
        lo, hi = photo[ring].min(axis=0), photo[ring].max(axis=0)
        seen, fill = photo[comp], out[comp]
        assert (fill >= np.minimum(lo, seen) - 1e-6).all()
        assert (fill <= np.maximum(hi, seen) + 1e-6).all()


def _outside_hull(colours, ring_colours, tol):
    eq = ConvexHull(ring_colours).equations
    return (colours @ eq[:, :-1].T + eq[:, -1] > tol).any(axis=1)


def test_navier_stokes_colours_inside_the_neighbours_hull():
    """A colour photo with text: every filled colour inside the hull of its cluster's ring
    colours (0.9 of a level allowed for the rounding), and each channel of the colour fill
    as good as the same method on that channel alone (a grey image)."""
    from skimage import data

    photo = np.ascontiguousarray(data.astronaut()[:96, 320:416])  # foliage-like texture
    mask = _text(photo.shape[:2])
    out = clpde.inpaint(photo, mask, channel_axis=-1, method="navier-stokes")
    outside = 0
    for comp, ring in _rings(mask):
        outside += int(_outside_hull(out[comp].astype(float), photo[ring].astype(float), 0.9).sum())
    assert outside == 0
    for c in range(3):
        grey = clpde.inpaint(np.ascontiguousarray(photo[..., c]), mask, method="navier-stokes")
        err_c = np.abs(out[..., c].astype(float) - photo[..., c])[mask]
        err_g = np.abs(grey.astype(float) - photo[..., c])[mask]
        assert np.sqrt(np.mean(err_c**2)) <= np.sqrt(np.mean(err_g**2)) + 0.05
        assert err_c.max() <= err_g.max()


def test_limit_moves_a_colour_towards_the_ring_into_its_hull():
    """bounds.limit on its own: four colours around a hole, and a saturated fill."""
    data = np.zeros((3, 9, 9))
    colours = [(0.2, 0.3, 0.3), (0.7, 0.6, 0.5), (0.4, 0.5, 0.8), (0.5, 0.2, 0.4)]
    for (ys, xs), c in zip(
        [
            (slice(0, 5), slice(0, 5)),
            (slice(0, 5), slice(5, 9)),
            (slice(5, 9), slice(0, 5)),
            (slice(5, 9), slice(5, 9)),
        ],
        colours,
        strict=True,
    ):
        data[:, ys, xs] = np.array(c)[:, None, None]
    omega = np.zeros((9, 9), bool)
    omega[3:6, 3:6] = True
    fill = data.copy()
    fill[:, omega] = np.array([1.0, 0.0, 0.5])[:, None]  # far outside, in no channel's range
    out = bounds.limit(fill, data, omega, ring=3, hull=True)
    ring = ~omega & (ndimage.distance_transform_edt(~omega) <= 3)
    assert not _outside_hull(out[:, omega].T, data[:, ring].T, 1e-9).any()
    assert _outside_hull(fill[:, omega].T, data[:, ring].T, 1e-9).all()
    np.testing.assert_array_equal(out[:, ~omega], fill[:, ~omega])
