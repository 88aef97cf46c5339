"""ROF denoising: kernels against their numpy references, and the denoiser against its maths."""

import numpy as np
import pyopencl.array as cla
import pytest
from skimage import data, img_as_float
from skimage.metrics import peak_signal_noise_ratio
from skimage.restoration import denoise_tv_chambolle

import clpde
from clpde.fields import Field, Grid
from tests.reference import rof as ref


def padded_random(rng, shape, scale=1.0):
    return (scale * rng.standard_normal(shape)).astype(np.float32)


def structured(nc, ny, nx):
    """A bright square with a ramp: flat regions, a sharp edge and a gradient."""
    y, x = np.mgrid[0:ny, 0:nx]
    img = 0.2 + 0.6 * ((abs(x - nx / 2) < nx / 4) & (abs(y - ny / 2) < ny / 4)) + 0.01 * x
    return np.stack([img * (c + 1) / nc for c in range(nc)])


@pytest.fixture
def camera_noisy():
    clean = img_as_float(data.camera())[::2, ::2]  # 256 x 256 keeps the tests fast
    noisy = clean + np.random.default_rng(7).normal(0, 0.1, clean.shape)
    return clean, noisy


# ---- kernels against the references -----------------------------------------------------
@pytest.mark.parametrize("nc,ny,nx", [(1, 9, 13), (2, 16, 16), (1, 2, 3), (3, 1, 7)])
@pytest.mark.parametrize("kind", ["random", "structured"])
def test_dual_step_matches_reference(runtime, rng, nc, ny, nx, kind):
    grid = Grid(runtime, nx, ny, nc)
    shape = (nc, ny + 2, nx + 2, 2)
    if kind == "random":
        p, p_old = padded_random(rng, shape, 0.8), padded_random(rng, shape, 0.8)
        f = padded_random(rng, shape[:3])
    else:
        p = np.zeros(shape, np.float32)
        p_old = p.copy()
        f = ref.pad_neumann(structured(nc, ny, nx)).astype(np.float32)
    lam = np.linspace(3.0, 12.0, nc).astype(np.float32)
    beta = 0.37
    q = runtime.queue
    bufs = [cla.to_device(q, a.reshape(nc, grid.plane, 2)) for a in (p, p_old)]
    p_new = cla.zeros(q, (nc, grid.plane, 2), np.float32)
    f_dev, lam_dev = cla.to_device(q, f), cla.to_device(q, lam)
    grid.launch(
        grid.kernel("planar/rof.cl", "rof_dual_step"),
        bufs[0].data,
        bufs[1].data,
        p_new.data,
        f_dev.data,
        lam_dev.data,
        np.float32(beta),
    )
    got = p_new.get().reshape(shape)
    want = ref.dual_step(p.astype(float), p_old.astype(float), f.astype(float), lam, beta)
    np.testing.assert_allclose(got, want, atol=2e-5, rtol=1e-5)


@pytest.mark.parametrize("nc,ny,nx", [(1, 9, 13), (2, 5, 40)])
def test_dual_rows_and_lambda_match_reference(runtime, rng, nc, ny, nx):
    grid = Grid(runtime, nx, ny, nc)
    shape = (nc, ny + 2, nx + 2, 2)
    p = padded_random(rng, shape, 0.5)
    f = padded_random(rng, shape[:3])
    u_before = padded_random(rng, shape[:3])
    lam = np.linspace(2.0, 5.0, nc).astype(np.float32)
    q = runtime.queue
    p_dev, f_dev, lam_dev = (cla.to_device(q, a) for a in (p.reshape(nc, grid.plane, 2), f, lam))
    u_dev = cla.to_device(q, u_before)
    partial = cla.empty(q, nc * 4 * ny, np.float32)
    grid.launch(
        grid.kernel("planar/rof.cl", "rof_dual_rows"),
        p_dev.data,
        f_dev.data,
        lam_dev.data,
        u_dev.data,
        partial.data,
    )
    u_want, sums_want = ref.dual_rows(
        p.astype(float), f.astype(float), lam, u_before[:, 1:-1, 1:-1].astype(float)
    )
    np.testing.assert_allclose(grid.interior(u_dev.get()), u_want, atol=1e-5, rtol=1e-5)
    rows = partial.get().reshape(nc, 4, ny)
    sums = np.concatenate([rows[:, :3].sum(axis=2), rows[:, 3:].max(axis=2)], axis=1)
    np.testing.assert_allclose(sums, sums_want, rtol=1e-4)

    sigma2 = np.linspace(0.01, 0.02, nc)
    if nc > 1:
        sigma2[-1] = np.inf  # a channel whose lambda is held
    inv = cla.to_device(q, (1 / (nx * ny * sigma2)).astype(np.float32))
    grid.kernel("planar/rof.cl", "rof_dual_lambda")(
        q, (nc,), None, partial.data, lam_dev.data, np.int32(ny), inv.data, np.float32(1e-6)
    )
    np.testing.assert_allclose(
        lam_dev.get(), ref.dual_lambda(sums_want[:, 0], lam, nx * ny, sigma2, 1e-6), rtol=1e-4
    )


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_gradient_kernels_match_reference(runtime, rng, kind):
    nc, ny, nx = 2, 12, 17
    grid = Grid(runtime, nx, ny, nc)
    u = rng.random((nc, ny, nx)) if kind == "random" else structured(nc, ny, nx)
    u0 = u + 0.05 * rng.standard_normal(u.shape)
    cur, orig = Field.from_host(grid, u), Field.from_host(grid, u0)
    nxt = Field.empty(grid)
    lam = np.array([4.0, 9.0], np.float32)
    lam_dev = cla.to_device(runtime.queue, lam)
    eps, dt = 0.05, 0.01
    grid.launch(
        grid.kernel("planar/planar.cl", "planar_rof_step"),
        cur.data.data,
        nxt.data.data,
        orig.data.data,
        lam_dev.data,
        np.float32(dt),
        np.float32(eps * eps),
    )
    want = ref.rof_step(ref.pad_neumann(u), ref.pad_neumann(u0), lam, dt, eps)
    np.testing.assert_allclose(nxt.to_host(), want, atol=1e-5)

    partial = cla.empty(runtime.queue, (nc, ny), np.float32)
    grid.launch(
        grid.kernel("planar/planar.cl", "planar_rof_lambda_rows"),
        cur.data.data,
        orig.data.data,
        partial.data,
        np.float32(eps * eps),
    )
    sigma2 = 0.01
    for c in range(nc):
        grid.kernel("planar/planar.cl", "planar_rof_lambda_finish")(
            runtime.queue,
            (1,),
            None,
            partial.data,
            lam_dev.data,
            np.int32(ny),
            np.float32(1 / (nx * ny * sigma2)),
            global_offset=(c,),
        )
    want_lam = ref.rof_lambda(ref.pad_neumann(u), ref.pad_neumann(u0), eps, sigma2)
    np.testing.assert_allclose(lam_dev.get(), want_lam, rtol=1e-4, atol=1e-6)


# ---- whole runs against the textbook algorithm and scikit-image ------------------------
def unit_range(rng, shape):
    """Float data whose min is 0 and max 1, so clpde's internal scaling is the identity."""
    f = rng.random(shape)
    f.flat[0], f.flat[1] = 0.0, 1.0
    return f


@pytest.mark.parametrize("shape", [(23, 31), (8, 5)])
def test_device_iterations_are_the_textbook_fgp(rng, shape):
    """Reflected ghosts reproduce the zero-flux gradient/divergence pair exactly."""
    f = unit_range(rng, shape)
    for steps in (1, 2, 17):
        got = clpde.denoise_tv(f, weight=0.25, max_steps=steps, tol=1e-12, dtype=np.float64)
        np.testing.assert_allclose(got, ref.fgp(f, 4.0, steps), atol=1e-12)
    got32 = clpde.denoise_tv(f, weight=0.25, max_steps=17, tol=1e-12)
    np.testing.assert_allclose(got32, ref.fgp(f, 4.0, 17), atol=2e-5)


def test_weight_mode_matches_scikit_image_minimiser(rng):
    """Same discrete TV and weight convention: both converge to the same minimiser."""
    clean = img_as_float(data.camera())[100:164, 200:264]
    noisy = clean + 0.1 * rng.standard_normal(clean.shape)
    ours, info = clpde.denoise_tv(noisy, weight=0.1, tol=1e-5, return_info=True)
    theirs = denoise_tv_chambolle(noisy, weight=0.1, eps=1e-9, max_num_iter=5000)
    assert info.converged
    assert np.sqrt(np.mean((ours - theirs) ** 2)) < 1e-3
    np.testing.assert_allclose(info.lam, [10.0], rtol=1e-6)
    # a minimiser: no lower energy than a long textbook run
    scale = noisy.max() - noisy.min()
    lam = scale / 0.1
    f = (noisy - noisy.min()) / scale
    u = (ours - noisy.min()) / scale
    assert ref.rof_energy(u, f, lam) <= ref.rof_energy(ref.fgp(f, lam, 2000), f, lam) * (1 + 1e-4)
    # more weight, smoother result
    smoother = clpde.denoise_tv(noisy, weight=0.3)

    def tv(u):
        return np.abs(np.diff(u, axis=0)).sum() + np.abs(np.diff(u, axis=1)).sum()

    assert tv(smoother) < tv(ours) < tv(noisy)


# ---- the mathematics on a photo ---------------------------------------------------------
@pytest.mark.parametrize("method", ["primal-dual", "gradient"])
def test_rof_raises_psnr_and_residual_reaches_sigma(camera_noisy, method):
    clean, noisy = camera_noisy
    out, info = clpde.denoise_tv(noisy, sigma=0.1, method=method, return_info=True)
    before = peak_signal_noise_ratio(clean, noisy, data_range=1)
    after = peak_signal_noise_ratio(clean, out, data_range=1)
    assert after > before + 5, (before, after)
    assert info.converged and info.method == method
    assert abs(info.residual_variance[0] / 0.1**2 - 1) < 0.03, info.residual_variance
    assert out.dtype == noisy.dtype and out.shape == noisy.shape


def test_sigma_mode_finds_the_weight_with_that_residual(camera_noisy):
    """lambda from the dynamic update, used as a fixed weight, reproduces the result."""
    _, noisy = camera_noisy
    out, info = clpde.denoise_tv(noisy, sigma=0.1, tol=1e-4, return_info=True)
    again = clpde.denoise_tv(noisy, weight=1 / info.lam[0], tol=1e-4)
    assert np.sqrt(np.mean((out - again) ** 2)) < 1e-3


def test_colour_is_denoised_per_channel(rng):
    clean = data.astronaut()[:96, :128]
    noisy = np.clip(clean + rng.normal(0, 20, clean.shape), 0, 255).astype(np.uint8)
    out, info = clpde.denoise_tv(
        noisy, sigma=20, channel_axis=-1, tol=1e-4, return_info=True, vectorial=False
    )
    assert out.dtype == np.uint8 and out.shape == noisy.shape
    assert info.lam.shape == (3,) and info.residual_variance.shape == (3,)
    for c in range(3):
        alone, alone_info = clpde.denoise_tv(noisy[..., c], sigma=20, tol=1e-4, return_info=True)
        assert np.abs(out[..., c].astype(int) - alone.astype(int)).max() <= 1
        np.testing.assert_allclose(info.lam[c], alone_info.lam[0], rtol=1e-3)
    # channel first gives the same
    first = clpde.denoise_tv(
        np.moveaxis(noisy, -1, 0), sigma=20, channel_axis=0, tol=1e-4, vectorial=False
    )
    assert np.abs(np.moveaxis(first, 0, -1).astype(int) - out.astype(int)).max() <= 1


def test_uint8_in_uint8_out_and_sigma_in_image_units(rng):
    clean = data.camera()[::4, ::4]
    noisy = np.clip(clean + rng.normal(0, 25, clean.shape), 0, 255).astype(np.uint8)
    original = noisy.copy()
    out, info = clpde.denoise_tv(noisy, sigma=25, return_info=True)
    assert out.dtype == np.uint8
    np.testing.assert_array_equal(noisy, original)  # input untouched
    assert abs(np.sqrt(info.residual_variance[0]) / 25 - 1) < 0.05
    err_before = np.abs(noisy.astype(float) - clean).mean()
    assert np.abs(out.astype(float) - clean).mean() < 0.6 * err_before


@pytest.mark.parametrize("method", ["primal-dual", "gradient"])
def test_sigma_larger_than_the_image_spread_gives_the_mean(method):
    flat = np.full((20, 30), 0.5)
    flat[5, 5] = 0.6
    out, info = clpde.denoise_tv(flat, sigma=1.0, method=method, return_info=True)
    np.testing.assert_allclose(out, flat.mean(), atol=1e-6)
    assert info.lam[0] == 0
    # a channel with less spread than sigma does not disturb the others
    pair = np.stack([flat, np.linspace(0, 1, 600).reshape(20, 30)], axis=-1)
    out, info = clpde.denoise_tv(
        pair, sigma=0.05, channel_axis=-1, return_info=True, vectorial=False
    )
    assert np.isfinite(out).all() and info.lam[0] == 0 < info.lam[1]
    assert info.converged and info.steps < 200


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"sigma": 0.1, "weight": 0.1}, "not both"),
        ({"sigma": -0.1}, "sigma must be a positive"),
        ({"sigma": float("nan")}, "sigma must be a positive"),
        ({"weight": 0}, "weight must be a positive"),
        ({"sigma": 0.1, "method": "newton"}, "unknown method"),
        ({"sigma": 0.1, "eps": 0.01}, "method='gradient'"),
        ({"sigma": 0.1, "tol": -1}, "tol must be a positive"),
    ],
)
def test_bad_parameters_raise(kwargs, match):
    with pytest.raises(clpde.InputError, match=match):
        clpde.denoise_tv(np.random.default_rng(0).random((8, 8)), **kwargs)


def test_bad_images_raise():
    bad = np.ones((8, 8))
    bad[2, 3] = np.nan
    with pytest.raises(clpde.InputError, match="NaN"):
        clpde.denoise_tv(bad, sigma=0.1)
    with pytest.raises(clpde.InputError, match="channel_axis"):
        clpde.denoise_tv(np.ones((4, 4, 3)), sigma=0.1)
    with pytest.raises(clpde.InputError, match="empty"):
        clpde.denoise_tv(np.ones((0, 4)), sigma=0.1)


def test_exported_from_planar():
    from clpde.planar import denoise_tv
    from clpde.planar.rof import DenoiseInfo

    assert denoise_tv is clpde.denoise_tv and DenoiseInfo.__module__ == "clpde.planar.rof"


def _unit(image):
    """Clipped to [0, 1] with both ends present, so the float scaling is the identity."""
    image = np.clip(image, 0.0, 1.0)
    image[0, 0], image[0, 1] = 0.0, 1.0
    return image


def test_stopping_does_not_depend_on_the_image_size():
    """A crop denoised on its own equals the same pixels denoised in a larger, smoother
    image, away from the crop's border: the stopping test is per pixel, not a sum that the
    settled pixels of a large image dilute."""
    from skimage.transform import rescale

    large = rescale(img_as_float(data.camera()), 1.5, order=3)  # smooth at the pixel scale
    large = _unit(large + 0.03 * np.random.default_rng(3).standard_normal(large.shape))
    y0, x0 = 230, 230
    crop = _unit(large[y0 : y0 + 300, x0 : x0 + 300].copy())
    whole = clpde.denoise_tv(large, weight=0.1)[y0 : y0 + 300, x0 : x0 + 300]
    alone = clpde.denoise_tv(crop, weight=0.1)
    assert np.abs(whole - alone)[60:-60, 60:-60].mean() <= 0.002
