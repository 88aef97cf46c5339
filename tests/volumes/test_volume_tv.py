"""3D TV denoising (clpde/volumes/tv.py, kernels/volumes/volume.cl): the kernels against the
numpy reference of the same scheme, the known answer of a ball (in physical units, with thick
slices), the exact rescaling that spacing makes, and clpde.denoise_tv's dispatch."""

import numpy as np
import pytest

import clpde
from clpde.errors import DeviceMemoryError
from clpde.volumes.tv import denoise_tv_volume
from tests.reference import volumes as ref


def _unit(rng, shape):
    """Random data spanning exactly [0, 1], so the kernels' scaling is the identity."""
    v = rng.random(shape)
    return (v - v.min()) / (v.max() - v.min())


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (2.0, 1.0, 0.5)])
def test_kernels_match_the_reference_iteration_for_iteration(rng, spacing):
    f = _unit(rng, (6, 7, 9))
    out, steps, *_ = denoise_tv_volume(f, weight=0.2, spacing=spacing, max_steps=25, tol=1e-12)
    assert steps == 25
    expected = ref.tv_fgp(f[None], 5.0, spacing, 25)[0]
    np.testing.assert_allclose(out, expected, atol=2e-5)


@pytest.mark.parametrize("vectorial", [True, False])
def test_channels_coupled_or_not_match_the_reference(rng, vectorial):
    f = _unit(rng, (5, 6, 7, 2))
    out, *_ = denoise_tv_volume(
        f, weight=0.25, channel_axis=-1, max_steps=20, tol=1e-12, vectorial=vectorial
    )
    expected = ref.tv_fgp(np.moveaxis(f, -1, 0), 4.0, (1, 1, 1), 20, vectorial=vectorial)
    np.testing.assert_allclose(out, np.moveaxis(expected, 0, -1), atol=2e-5)
    # coupling changes the answer: the test can tell the two apart
    other, *_ = denoise_tv_volume(
        f, weight=0.25, channel_axis=-1, max_steps=20, tol=1e-12, vectorial=not vectorial
    )
    assert np.abs(other - out).max() > 1e-3


def test_a_ball_with_thick_slices_loses_3_over_lambda_r():
    """ROF of the indicator of a ball of radius R in R^3 is (1 - 3 / (lambda R)) on the ball
    (it is calibrable): with slices twice as thick as pixels, R in physical units."""
    n, radius, lam = 32, 8.0, 1.0
    h = (2.0, 1.0, 1.0)
    z, y, x = np.indices((n // 2, n, n)).astype(float)
    z, y, x = (z + 0.5) * h[0] - n / 2, y + 0.5 - n / 2, x + 0.5 - n / 2
    r2 = x * x + y * y + z * z
    ball = (r2 < radius**2).astype(float)
    u = clpde.denoise_tv(ball, weight=1 / lam, spacing=h, tol=1e-5, max_steps=3000)
    drop = 1 - u[r2 < (radius / 2) ** 2].mean()
    assert drop == pytest.approx(3 / (lam * radius), rel=0.08)
    assert u[r2 > (radius + 2) ** 2].max() < 0.05  # outside stays dark


def test_spacing_scales_the_strength_exactly_along_its_axis(rng):
    """TV of a volume varying along z alone is 1/hz times the unit one, so spacing hz at
    weight w solves the problem of unit spacing at weight w / hz; a volume varying along x
    alone does not see hz."""
    profile = _unit(rng, 12)
    along_z = np.broadcast_to(profile[:, None, None], (12, 5, 6)).copy()
    thick = clpde.denoise_tv(along_z, weight=0.2, spacing=(2, 1, 1), tol=1e-6, max_steps=4000)
    unit = clpde.denoise_tv(along_z, weight=0.1, spacing=(1, 1, 1), tol=1e-6, max_steps=4000)
    np.testing.assert_allclose(thick, unit, atol=1e-3)
    other = clpde.denoise_tv(along_z, weight=0.2, spacing=(1, 1, 1), tol=1e-6, max_steps=4000)
    assert np.abs(other - thick).max() > 0.02
    along_x = np.ascontiguousarray(np.moveaxis(along_z, 0, -1))  # (5, 6, 12)
    np.testing.assert_allclose(
        clpde.denoise_tv(along_x, weight=0.2, spacing=(3, 1, 1), tol=1e-6, max_steps=4000),
        clpde.denoise_tv(along_x, weight=0.2, spacing=(1, 1, 1), tol=1e-6, max_steps=4000),
        atol=1e-4,
    )


def test_denoise_tv_takes_volumes_with_sigma_and_keeps_dtype(rng):
    z, y, x = np.indices((16, 20, 18))
    clean = np.where((z - 8) ** 2 + (y - 10) ** 2 + (x - 9) ** 2 < 36, 200, 50).astype(np.uint8)
    noisy = np.clip(clean + rng.normal(0, 20, clean.shape), 0, 255).astype(np.uint8)
    before = noisy.copy()
    out, info = clpde.denoise_tv(noisy, sigma=20, return_info=True)
    assert out.dtype == np.uint8 and out.shape == noisy.shape
    assert (noisy == before).all()
    err = lambda v: np.abs(v.astype(float) - clean).mean()  # noqa: E731
    assert err(out) < err(noisy) / 3
    assert info.converged and info.sigma[0] == 20
    assert np.sqrt(info.residual_variance[0]) == pytest.approx(20, rel=0.15)
    # estimated sigma: close to the noise added
    _, est = clpde.denoise_tv(noisy, return_info=True)
    assert est.sigma_estimated and est.sigma[0] == pytest.approx(20, rel=0.2)


def test_colour_volume_takes_channel_axis(rng):
    vol = _unit(rng, (3, 8, 9, 9))  # channels first
    out = clpde.denoise_tv(vol, weight=0.1, channel_axis=0)
    assert out.shape == vol.shape
    assert out.std() < vol.std()


@pytest.mark.parametrize(
    "image,kwargs,match",
    [
        (np.ones((4, 4, 3)), {}, "channel_axis=-1 for a colour image"),
        (np.ones((4, 4, 4, 2)), {}, "4 dimensions"),
        (np.ones((4, 4, 4)), {"spacing": (1, 0, 1)}, "spacing"),
        (np.ones((4, 4, 4)), {"spacing": (1, 1)}, "spacing"),
        (np.ones((4, 4, 4)), {"method": "gradient"}, "only; leave out method"),
        (np.ones((4, 4, 4)), {"sigma": 1, "weight": 1}, "not both"),
    ],
)
def test_bad_volume_input_gives_one_line(image, kwargs, match):
    with pytest.raises(clpde.InputError, match=match):
        clpde.denoise_tv(image, **kwargs)


def test_a_colour_image_still_takes_the_planar_path(rng):
    image = _unit(rng, (16, 16, 3))
    assert clpde.denoise_tv(image, weight=0.1, channel_axis=-1).shape == (16, 16, 3)


@pytest.mark.parametrize("channels", [1, 2])
def test_slabs_equal_the_whole_volume(rng, monkeypatch, channels):
    from clpde.volumes import tv

    clean = np.zeros((21, 8, 9, channels))
    clean[5:15, 2:6, 3:7] = 0.8
    noisy = clean + 0.1 * rng.standard_normal(clean.shape)
    axis = -1 if channels > 1 else None
    vol = noisy if channels > 1 else noisy[..., 0]
    run = lambda: denoise_tv_volume(  # noqa: E731
        vol, spacing=(2, 1, 1), channel_axis=axis, dtype=np.float64
    )
    whole, steps, *_ = run()
    made = []
    real_slab = tv._Slab
    monkeypatch.setattr(tv, "TILE_PLANES", 15)  # 3 own planes and 6 ghosts either side
    monkeypatch.setattr(tv, "_Slab", lambda *a: made.append(a[4:]) or real_slab(*a))
    tiled, tiled_steps, *_ = run()
    assert len(set(made)) == 7 and len(made) > 7  # 7 slabs, several rounds
    np.testing.assert_allclose(tiled, whole, atol=1e-9)
    assert tiled_steps == steps > 5
    assert np.abs(whole - vol).max() > 0.1  # it denoised


def test_too_few_planes_for_the_ghosts_are_refused(monkeypatch):
    from clpde.volumes import tv

    monkeypatch.setattr(tv, "TILE_PLANES", 12)
    with pytest.raises(DeviceMemoryError, match="lower check_every"):
        clpde.denoise_tv(np.random.default_rng(0).random((20, 5, 6)), 0.1, spacing=(1, 1, 1))
