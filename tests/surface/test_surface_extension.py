"""Extension along normals (PDE of section 4.2 and closest point) and reinitialisation of psi
on the device: kernels against numpy references, results against the exact geometry."""

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.errors import InputError
from clpde.surface import ImplicitSurface
from tests.reference import surface as ref


def band_host(band):
    return band.indices.get()[: band.n].astype(np.int64)


@pytest.fixture(scope="module")
def sphere():
    return ImplicitSurface.sphere(1.0, 0.1)


def radius(s):
    x, y, z = s.coordinates()
    return np.broadcast_to(np.sqrt(x**2 + y**2 + z**2), s.shape)


def test_extend_pde_step_matches_reference(sphere, rng):
    s = sphere
    g, q = s.grid, s.runtime.queue
    x, y, z = s.coordinates()
    structured = g.pad(np.broadcast_to(x * y + (z > 0), s.shape)[None])
    for u in (rng.standard_normal((2,) + g.padded_shape), structured):
        u32 = np.ascontiguousarray(u, np.float32)
        src, dst = cla.to_device(q, u32), cla.zeros(q, u.shape, np.float32)
        g.launch_list(
            g.kernel("surface/extend.cl", "extend_pde_step", NC=u.shape[0]),
            s.ext_band,
            src.data,
            dst.data,
            s.psi_dev.data,
            g.scalar(0.5),
            g.scalar(s.spacing),
            *g.strides(),
        )
        band = band_host(s.ext_band)
        expect = ref.extend_pde_step(u32.astype(np.float64), s.psi_dev.get(), band, 0.5, s.spacing)
        got = dst.get().reshape(u.shape[0], -1)[:, band]
        np.testing.assert_allclose(got, expect, atol=2e-5 * max(1, np.abs(expect).max()))


def test_reinit_step_matches_reference(sphere, rng):
    s = sphere
    g, q = s.grid, s.runtime.queue
    phi0 = (s.psi_dev.get() * (1 + 0.3 * rng.random(g.padded_shape))).astype(np.float32)
    phi = (phi0 + 0.01 * rng.standard_normal(phi0.shape)).astype(np.float32)
    everywhere = g.band(s.psi_dev, np.inf)
    out = cla.to_device(q, phi)
    g.launch_list(
        g.kernel("surface/reinit.cl", "reinit_step"),
        everywhere,
        cla.to_device(q, phi).data,
        out.data,
        cla.to_device(q, phi0).data,
        g.scalar(0.3),
        g.scalar(1 / s.spacing),
        *g.strides(),
    )
    band = band_host(everywhere)
    assert band.size == np.prod(s.shape)
    expect = ref.reinit_step(phi, phi0, band, 0.3, s.spacing)
    np.testing.assert_allclose(out.get().ravel()[band], expect, atol=1e-5)


@pytest.mark.parametrize("h", [0.1, 0.05])
def test_pde_extension_makes_data_constant_along_normals(h):
    s = ImplicitSurface.sphere(1.0, h)
    x, y, z = s.coordinates()
    r = radius(s)
    raw = np.broadcast_to(x * y + z, s.shape)  # varies along the normals
    with np.errstate(invalid="ignore", divide="ignore"):
        exact = x * y / r**2 + z / r
    near = np.abs(r - 1) < 3.4 * h
    pde = s.extend(raw, method="pde")
    cp = s.extend(raw)
    raw_err = np.abs(raw - exact)[near].max()
    assert np.abs(pde - exact)[near].max() < 0.25 * raw_err
    assert np.abs(cp - exact)[near].max() < 0.01 * raw_err
    # on the surface itself the data is kept (to the scheme's first order)
    on = np.abs(r - 1) < 0.5 * h
    assert np.abs(pde - raw)[on].max() < 2.5 * h


def test_reinitialisation_gives_a_distance_and_keeps_the_surface():
    s = ImplicitSurface.sphere(1.0, 0.1)
    x, _y, _z = s.coordinates()
    r = radius(s)
    bent = (r**2 - 1) * (1 + 0.3 * x)  # same zero level set, far from a distance
    again = ImplicitSurface.from_volume(bent, s.spacing, s.origin, reinitialize=True)
    band = np.abs(r - 1) < 0.4
    assert np.abs(again.psi - (r - 1))[band].max() < 0.3 * s.spacing
    assert np.abs(again.psi - (r - 1))[band].mean() < 0.05 * s.spacing
    # and the flows work on it: heat of xy on the reinitialised sphere
    u = again.field(lambda x, y, z: x * y)
    pts = np.array([[1.0, 0, 0], [0, 0.6, 0.8], [0.6, 0.8, 0], [0.48, 0.64, 0.6]])
    out = again.sample(again.heat(u, t=0.05), pts)
    assert np.abs(out - np.exp(-0.3) * pts[:, 0] * pts[:, 1]).max() < 0.01


def test_extend_rejects_unknown_methods(sphere):
    with pytest.raises(InputError, match="closest-point"):
        sphere.extend(np.zeros(sphere.shape), method="fast")
