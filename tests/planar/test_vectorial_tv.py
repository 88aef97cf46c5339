"""Colour-coupled (vectorial) TV denoising: its kernels against their numpy references, whole
runs against the textbook algorithm, and the model against its maths."""

import numpy as np
import pyopencl.array as cla
import pytest
from skimage import data, img_as_float

import clpde
from clpde.fields import Grid
from tests.reference import rof as ref


def unit_rgb(rng, shape):
    f = rng.random(shape)
    f.flat[0], f.flat[1] = 0.0, 1.0  # the float scaling is then the identity
    return f


@pytest.mark.parametrize("nc,ny,nx", [(3, 7, 11), (2, 12, 5)])
def test_vectorial_step_matches_reference(runtime, rng, nc, ny, nx):
    grid = Grid(runtime, nx, ny, nc)
    cells = Grid(runtime, nx, ny, 1)
    shape = (nc, ny + 2, nx + 2, 2)
    p = (0.6 * rng.standard_normal(shape)).astype(np.float32)
    p_old = (0.6 * rng.standard_normal(shape)).astype(np.float32)
    f = rng.standard_normal(shape[:3]).astype(np.float32)
    lam, beta = 4.5, 0.3
    q = runtime.queue
    bufs = [cla.to_device(q, a.reshape(nc, grid.plane, 2)) for a in (p, p_old)]
    p_new = cla.zeros(q, (nc, grid.plane, 2), np.float32)
    f_dev = cla.to_device(q, f)
    lam_dev = cla.to_device(q, np.full(nc, lam, np.float32))
    cells.launch(
        grid.kernel("planar/rof.cl", "rof_dual_step_vec"),
        bufs[0].data,
        bufs[1].data,
        p_new.data,
        f_dev.data,
        lam_dev.data,
        np.float32(beta),
        np.int32(nc),
    )
    want = ref.dual_step_vec(p.astype(float), p_old.astype(float), f.astype(float), lam, beta)
    np.testing.assert_allclose(p_new.get().reshape(shape), want, atol=2e-5, rtol=1e-5)
    # some cells were projected, others not: both branches are compared
    norms = np.sqrt((want[:, 1:-1, 1:-1] ** 2).sum(axis=(0, 3)))
    assert (norms > 0.999).any() and (norms < 0.99).any()


def test_vectorial_lambda_matches_reference(runtime):
    nc, ny = 3, 6
    partial = np.zeros((nc, 4, ny), np.float32)
    partial[:, 0] = np.arange(nc * ny).reshape(nc, ny) * 0.01 + 0.1
    q = runtime.queue
    part_dev = cla.to_device(q, partial.ravel())
    lam_dev = cla.to_device(q, np.full(nc, 3.0, np.float32))
    n, sigma2 = 40 * ny, 0.004
    runtime.kernel("planar/rof.cl", "rof_dual_lambda_vec", np.float32)(
        q,
        (1,),
        (1,),
        part_dev.data,
        lam_dev.data,
        np.int32(ny),
        np.int32(nc),
        np.float32(1 / (n * nc * sigma2)),
        np.float32(1e-6),
    )
    want = ref.dual_lambda_vec(partial[:, 0].sum(axis=1), 3.0, n, sigma2, 1e-6)
    np.testing.assert_allclose(lam_dev.get(), np.full(nc, want), rtol=1e-5)


def test_device_iterations_are_the_textbook_vectorial_fgp(rng):
    f = unit_rgb(rng, (13, 17, 3))
    for steps in (1, 3, 20):
        got = clpde.denoise_tv(
            f, weight=0.2, channel_axis=-1, max_steps=steps, tol=1e-12, dtype=np.float64
        )
        want = np.moveaxis(ref.fgp_vec(np.moveaxis(f, -1, 0), 5.0, steps), 0, -1)
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_replicated_grey_is_grey_tv_with_scaled_weight(rng):
    """TV_vec(u, u, u) = sqrt(3) TV(u) and |(u,u,u) - (f,f,f)|^2 = 3 |u - f|^2, so the
    minimiser of the replicated problem of weight w is the grey one of weight w / sqrt(3)."""
    grey = unit_rgb(rng, (40, 48))
    rgb = np.repeat(grey[..., None], 3, axis=-1)
    weight = 0.15
    colour = clpde.denoise_tv(
        rgb, weight=weight, channel_axis=-1, tol=1e-6, max_steps=4000, dtype=np.float64
    )
    alone = clpde.denoise_tv(
        grey, weight=weight / np.sqrt(3), tol=1e-6, max_steps=4000, dtype=np.float64
    )
    for c in range(3):
        np.testing.assert_allclose(colour[..., c], alone, atol=2e-4)


def test_vectorial_is_the_default_for_colour_and_differs_from_per_channel(rng):
    clean = img_as_float(data.astronaut())[100:164, 200:264]
    noisy = np.clip(clean + 0.08 * rng.standard_normal(clean.shape), 0, 1)
    default = clpde.denoise_tv(noisy, weight=0.1, channel_axis=-1)
    coupled = clpde.denoise_tv(noisy, weight=0.1, channel_axis=-1, vectorial=True)
    separate = clpde.denoise_tv(noisy, weight=0.1, channel_axis=-1, vectorial=False)
    np.testing.assert_array_equal(default, coupled)
    assert np.abs(coupled - separate).max() > 0.01


def test_vectorial_edges_line_up_across_channels():
    """A colour edge whose contrast is strong in red and weak in green and blue: per-channel
    TV flattens the weak channels' edge and keeps red's, vectorial TV keeps all three."""
    img = np.zeros((32, 32, 3))
    img[:, 16:, 0] = 1.0
    img[:, 16:, 1:] = 0.08
    edge = lambda u, c: float(u[:, 18:, c].mean() - u[:, :14, c].mean())  # noqa: E731
    coupled = clpde.denoise_tv(img, weight=1.0, channel_axis=-1, vectorial=True, tol=1e-6)
    separate = clpde.denoise_tv(img, weight=1.0, channel_axis=-1, vectorial=False, tol=1e-6)
    assert edge(coupled, 1) > 0.5 * 0.08 > edge(separate, 1)


def test_vectorial_sigma_fits_the_mean_noise_variance(rng):
    clean = img_as_float(data.astronaut())[::4, ::4]
    noisy = clean + 0.05 * rng.standard_normal(clean.shape)
    out, info = clpde.denoise_tv(noisy, sigma=0.05, channel_axis=-1, tol=1e-5, return_info=True)
    assert np.ptp(info.lam) == 0  # one shared lambda
    np.testing.assert_allclose(info.residual_variance.mean(), 0.05**2, rtol=0.05)
    np.testing.assert_allclose(info.sigma, [0.05] * 3)


def test_vectorial_refused_with_the_gradient_method():
    with pytest.raises(clpde.InputError, match="primal-dual"):
        clpde.denoise_tv(
            np.zeros((8, 8, 3)), weight=0.1, channel_axis=-1, method="gradient", vectorial=True
        )
