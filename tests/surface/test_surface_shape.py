"""Principal curvature directions and Turk's reaction-diffusion on implicit surfaces."""

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.errors import InputError
from clpde.surface import ImplicitSurface, textures
from clpde.surface.storage import _offsets
from tests.reference import surface as ref


def band_host(band):
    return band.indices.get()[: band.n].astype(np.int64)


@pytest.fixture(scope="module")
def torus():
    with pytest.warns(UserWarning, match="too coarse"):
        return ImplicitSurface.torus(1.0, 0.4, spacing=0.1)


def test_principal_directions_kernel_matches_reference(torus):
    s = torus
    g, q = s.grid, s.runtime.queue
    band = s.ext_band
    dirs = cla.empty(q, (6, band.n), np.float32)
    curv = cla.empty(q, (2, band.n), np.float32)
    g.launch_list(
        g.kernel("surface/shape.cl", "shape_principal_directions"),
        band,
        s.psi_dev.data,
        g.scalar(1 / s.spacing),
        dirs.data,
        curv.data,
        *g.strides(),
    )
    want_dirs, want_curv = ref.principal_directions(s.psi_dev.get(), band_host(band), 1 / s.spacing)
    got = dirs.get()
    ok = np.all(np.isfinite(want_dirs), axis=0)  # the torus's core circle has no normal
    got, want_dirs, want_curv = got[:, ok], want_dirs[:, ok], want_curv[:, ok]
    # directions up to sign (atan2 on a near-tie may flip one): compare |cos| of the angle
    for first in (0, 3):
        cos = np.abs((got[first : first + 3] * want_dirs[first : first + 3]).sum(axis=0))
        assert np.quantile(cos, 0.999) > 0.999 and np.median(cos) > 0.99999
    np.testing.assert_allclose(curv.get()[:, ok], want_curv, rtol=1e-3, atol=2e-3)


def test_principal_curvatures_and_directions_of_a_torus():
    s = ImplicitSurface.torus(1.0, 0.4, spacing=0.05)
    major, minor, curv = s.principal_directions()
    pts = np.array(
        [[1.4, 0, 0], [0, -1.4, 0], [0.6, 0, 0], [0, 1.0, 0.4], [-0.99, 0.99, 0.4 * 0 + 0.0]]
    )
    pts[4] = np.array([-1, 1, 0]) / np.sqrt(2) * 1.4
    k = s.sample(curv, pts)
    np.testing.assert_allclose(k[:, 0], 2.5, atol=0.02)  # around the tube: 1 / r
    expect = np.array([1 / 1.4, 1 / 1.4, -1 / 0.6, 0.0, 1 / 1.4])  # cos v / (R + r cos v)
    np.testing.assert_allclose(k[:, 1], expect, atol=0.02)
    # at the outer equator the minor direction runs around the axis, the major along z
    idx = np.rint((pts - s.origin) / s.spacing).astype(int)
    for p, (i, j, kk) in zip(pts[[0, 1, 4]], idx[[0, 1, 4]], strict=False):
        around = np.array([-p[1], p[0], 0]) / np.hypot(p[0], p[1])
        assert abs(minor[:, kk, j, i] @ around) > 0.99
        assert abs(major[:, kk, j, i][2]) > 0.99


def test_turk_step_matches_reference(rng):
    s = ImplicitSurface.sphere(1.0, 0.2)
    g, q = s.grid, s.runtime.queue
    u = (4 + rng.standard_normal((2,) + g.padded_shape)).astype(np.float32)
    beta = (12 + 0.1 * rng.uniform(-1, 1, g.padded_shape)).astype(np.float32)
    d = rng.standard_normal((3,) + g.padded_shape)
    d = (d / np.sqrt((d**2).sum(axis=0))).astype(np.float32)
    for along in (False, True):
        dst = cla.zeros(q, u.shape, np.float32)
        offsets = _offsets(g, 2)
        g.launch_runs(
            g.kernel("surface/heat.cl", "heat_turk_step", ALONG=int(along)),
            s.step_runs,
            cla.to_device(q, u).data,
            dst.data,
            s.psi_dev.data,
            cla.to_device(q, d).data,
            cla.to_device(q, beta).data,
            g.scalar(1.0),
            g.scalar(0.125),
            g.scalar(1 / 32),
            g.scalar(0.0125),
            *offsets,
            *g.strides(),
        )
        band = band_host(s.node_band)
        expect = ref.turk_step(
            u.astype(np.float64),
            s.psi_dev.get(),
            band,
            beta,
            1.0,
            0.125,
            1 / 32,
            0.0125,
            [int(o) for o in offsets],
            d.astype(np.float64) if along else None,
        )
        np.testing.assert_allclose(dst.get().reshape(2, -1)[:, band], expect, atol=3e-5)


def test_turk_equilibrium_is_steady_and_noise_grows_a_pattern():
    s = ImplicitSurface.sphere(1.0, 0.1)
    flat = dict(textures.TURK, beta_spread=0.0)
    ab = s.reaction_diffusion(50, params=flat)
    band = np.abs(s.psi) < 2 * s.spacing
    # a = b = 4 solves 16 - ab = 0 and ab - b - 12 = 0
    assert np.abs(ab[:, band] - 4).max() < 1e-4
    for params, iterations in ((textures.TURK, 1500), (None, 1500)):  # Turk's, Figure 4.7's
        ab = s.reaction_diffusion(iterations, params=params)
        spread = ab[0, band].max() - ab[0, band].min()
        assert spread > 0.4  # Turing instability: the 0.1 irregularity in beta grew a pattern
        # b is clamped at 0 on the nodes; the tricubic re-extension may undershoot a little
        # next to the clamped spots
        assert ab[1, band].min() >= -0.03 * ab[1, band].max()


def test_turk_rejects_unstable_rates():
    s = ImplicitSurface.sphere(1.0, 0.2)
    with pytest.raises(InputError, match="stability limit"):
        s.reaction_diffusion(1, params=textures.THESIS_FIG_4_7, dt=1.0)


def test_turk_linear_stability_wavelength():
    # Turk's rates (1/8, 1/32 per unit time, s = 0.2/16, beta = 12): about 9.9 cells
    assert textures.turk_linear_wavelength() == pytest.approx(9.93, abs=0.05)
    # a slower-diffusing inhibitor b gives a shorter pattern
    assert textures.turk_linear_wavelength(dict(textures.TURK, db=1 / 64)) < 9.9
