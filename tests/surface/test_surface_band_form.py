"""The band form of data on a surface (ImplicitSurface.band_indices): values at the extension
band's cells only, taken and returned by the flows in place of dense volumes."""

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.surface import ImplicitSurface


@pytest.fixture(scope="module")
def sphere():
    return ImplicitSurface.sphere(1.0, spacing=0.1)


def test_indices_coordinates_and_closest_points_are_the_band_cells(sphere):
    s = sphere
    idx = s.band_indices()
    band = np.flatnonzero(np.abs(s.psi) < s.outer * s.spacing)
    assert np.array_equal(idx, band)  # the extension band, in increasing order
    x, y, z = s.coordinates()
    xyz = np.stack([np.broadcast_to(c, s.shape).reshape(-1)[idx] for c in (x, y, z)], axis=1)
    assert np.array_equal(s.band_coordinates(), xyz)
    cx, cy, cz = s.closest_points_host()
    dense_cp = np.stack([c.reshape(-1)[idx] for c in (cx, cy, cz)], axis=1)
    assert np.allclose(s.band_closest_points(), dense_cp, atol=1e-12)
    # a sphere's closest points lie on it
    assert np.abs(np.linalg.norm(s.band_closest_points(), axis=1) - 1).max() < 1e-3


def test_band_values_and_from_band_convert_both_ways(sphere, rng):
    s = sphere
    u = rng.normal(size=(2,) + s.shape).astype(np.float32)
    b = s.band_values(u)
    assert b.shape == (2, s.ext_band.n) and b.dtype == np.float32
    back = s.from_band(b, fill=7.0)
    assert back.dtype == np.float32
    on = np.abs(s.psi) < s.outer * s.spacing
    assert np.array_equal(back[:, on], u[:, on]) and np.all(back[:, ~on] == 7.0)
    assert np.array_equal(s.band_values(u[0]), b[0])
    assert np.allclose(
        s.band_field(lambda x, y, z: x * y),
        s.band_values(s.field(lambda x, y, z: x * y)),
        atol=1e-12,
    )


@pytest.mark.parametrize("storage", ["lists", "bricks"])
def test_flows_in_band_form_give_the_dense_results_at_the_band_bitwise(sphere, rng, storage):
    s = sphere
    s.storage = storage
    try:
        u = rng.normal(size=s.shape)
        b = s.band_values(u)
        assert np.array_equal(s.heat(b, 0.02), s.band_values(s.heat(u, 0.02)))
        v = np.stack([u, -2 * u])
        assert np.array_equal(s.heat(s.band_values(v), 0.01), s.band_values(s.heat(v, 0.01)))
    finally:
        s.storage = "lists"
    assert np.array_equal(
        s.denoise_tv(b, sigma=0.3, t=0.02), s.band_values(s.denoise_tv(u, sigma=0.3, t=0.02))
    )
    assert np.array_equal(s.extend(b), s.band_values(s.extend(u)))
    pts = rng.normal(size=(20, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    assert np.array_equal(s.sample(b, pts), s.sample(u, pts))
    assert s.heat(b.astype(np.float32), 0.01).dtype == np.float32


def test_band_form_errors_name_the_shapes(sphere):
    s = sphere
    with pytest.raises(InputError, match="band form"):
        s.heat(np.zeros(s.ext_band.n + 1), 0.01)
    with pytest.raises(InputError, match="band form"):
        s.from_band(np.zeros(3))
    bad = np.zeros(s.ext_band.n)
    bad[5] = np.nan
    with pytest.raises(InputError, match="NaN"):
        s.heat(bad, 0.01)


def test_harmonic_maps_take_the_band_form(sphere):
    s = sphere
    v = s.field(lambda x, y, z: [x + 0 * y, y + 0 * z, z + 0 * x])
    v /= np.sqrt((v**2).sum(0)) + 1e-12
    v[:, np.abs(s.psi) > 0.5] = 1 / np.sqrt(3)
    assert np.array_equal(
        s.harmonic_map(s.band_values(v), 0.005), s.band_values(s.harmonic_map(v, 0.005))
    )
