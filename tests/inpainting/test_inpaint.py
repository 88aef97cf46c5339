"""clpde.inpaint: its mathematics (steady states of thesis chapter 3) and its contract."""

import numpy as np
import pytest

import clpde
from clpde.inpainting import multiresolution as mr
from clpde.inpainting.api import Inpainting
from clpde.inpainting.colour import rgb_to_rho_phi_psi, rho_phi_psi_to_rgb


def _edge_image(n=48, angle=0.35, width=1.5):
    """A soft straight edge: every isophote is a straight line."""
    y, x = np.mgrid[0:n, 0:n].astype(float)
    t = (x - n / 2) * np.cos(angle) + (y - n / 2) * np.sin(angle)
    return 0.2 + 0.6 / (1 + np.exp(-t / width))


def _disc(n, cy, cx, r):
    y, x = np.mgrid[0:n, 0:n]
    return np.hypot(y - cy, x - cx) <= r


def _err(a, b, m):
    return np.abs(a.astype(float) - b.astype(float))[m]


# ---- mathematics ---------------------------------------------------------------------------
def test_straight_isophotes_continue_across_a_hole():
    image = _edge_image()
    hole = _disc(48, 24, 24, 6)
    out, info = clpde.inpaint(image, hole, levels=1, return_info=True)
    err = _err(out, image, hole)
    assert err.max() < 0.03 and err.mean() < 0.01, (err.max(), err.mean())
    assert info.converged and info.steps > 0 and info.levels == 1
    # From the harmonic fill, much further off, the flow (not the start) does the work.
    start = clpde.inpaint(image, hole, levels=1, max_steps=0, fill="diffusion")
    flowed = clpde.inpaint(image, hole, levels=1, fill="diffusion")
    assert _err(start, image, hole).mean() > 4 * _err(flowed, image, hole).mean()
    assert _err(flowed, image, hole).max() < 0.03
    # The default (biharmonic) start is better than the harmonic one, and the flow improves it.
    start = clpde.inpaint(image, hole, levels=1, max_steps=0)
    assert _err(start, image, hole).mean() > 2 * err.mean()


def test_cw_and_ccw_rotations_reach_the_same_steady_state():
    # Figure 3.9: the intermediate states differ, the steady state does not.
    image = _edge_image(32, angle=1.0)
    hole = np.zeros(image.shape, bool)
    hole[11:21, 10:22] = True
    runs = {}
    for rot in ("ccw", "cw"):
        early = clpde.inpaint(image, hole, rotation=rot, fill="mean", max_steps=68, tol=0)
        final, info = clpde.inpaint(
            image,
            hole,
            rotation=rot,
            fill="mean",
            tol=1e-4,
            mean_tol=0,
            max_steps=8000,
            return_info=True,
        )
        assert info.converged
        runs[rot] = early, final
    early_gap = np.abs(runs["ccw"][0] - runs["cw"][0]).max()
    final_gap = np.abs(runs["ccw"][1] - runs["cw"][1]).max()
    assert final_gap < 0.015 and final_gap < early_gap / 5, (final_gap, early_gap)
    assert _err(runs["ccw"][1], image, hole).mean() < 0.015


def test_annular_region_joins_inner_and_outer_contours():
    # Figure 3.8: Omega is a ring; the dark bar crossing it must join its inner and outer
    # pieces through the ring, and the background must stay light.
    n = 64
    _, x = np.mgrid[0:n, 0:n]
    image = np.where(np.abs(x - 30.5) <= 3, 0.1, 0.9)
    ring = _disc(n, 32, 31, 15) & ~_disc(n, 32, 31, 6)
    out = clpde.inpaint(image, ring)
    bar = ring & (np.abs(x - 30.5) <= 1.5)
    background = ring & (np.abs(x - 30.5) >= 6)
    assert out[bar].max() < 0.4, out[bar].max()
    assert out[background].min() > 0.6, out[background].min()
    # Every row of the ring that the bar crosses is dark at the bar's centre.
    assert (out[ring[:, 30] | ring[:, 31], 30:32] < 0.4).all()


def test_levels_follow_the_mask_thickness_and_coarse_start_works():
    thin = np.zeros((96, 96), bool)
    thin[40:43, :] = True
    assert mr.auto_levels(thin) == 1
    blob = _disc(96, 48, 48, 15)
    assert mr.auto_levels(blob) >= 2
    image = _edge_image(96, angle=0.6, width=3)
    out, info = clpde.inpaint(image, blob, method="transport", return_info=True)
    assert info.levels >= 2 and len(info.steps_per_level) == info.levels
    assert _err(out, image, blob).mean() < 0.05


def test_pyramid_geometry():
    data = np.arange(2 * 7 * 9, dtype=float).reshape(2, 7, 9)
    omega = np.zeros((7, 9), bool)
    omega[2, 3] = True
    coarse, comega = mr.downsample(data, omega)
    assert coarse.shape == (2, 4, 5) and comega.shape == (4, 5)
    assert comega[1, 1] and comega.sum() == 1
    assert coarse[0, 0, 0] == pytest.approx(data[0, :2, :2].mean())
    up = mr.upsample(coarse, (7, 9))
    assert up.shape == (2, 7, 9)
    ramp = np.broadcast_to(np.arange(16.0), (1, 16, 16))
    assert np.allclose(
        mr.upsample(mr.downsample(ramp, np.zeros((16, 16), bool))[0], (16, 16))[:, :, 1:-1],
        ramp[:, :, 1:-1],
    )


def test_convergence_check_stops_early_and_fixed_steps_run_fully():
    image = _edge_image(32)
    hole = _disc(32, 16, 16, 4)
    _, info = clpde.inpaint(image, hole, tol=1e-2, return_info=True)
    assert info.converged and info.steps < 3000
    _, info = clpde.inpaint(image, hole, tol=0, mean_tol=0, max_steps=170, return_info=True)
    assert not info.converged and info.steps == 170
    # The mean-change test alone also ends a run, and earlier than a strict largest-change one.
    _, by_mean = clpde.inpaint(image, hole, tol=0, mean_tol=1e-3, return_info=True)
    _, by_max = clpde.inpaint(image, hole, tol=1e-5, mean_tol=0, max_steps=6000, return_info=True)
    assert by_mean.converged and by_mean.steps < by_max.steps


# ---- colour --------------------------------------------------------------------------------
def test_rho_phi_psi_round_trip():
    rng = np.random.default_rng(0)
    rgb = rng.random((3, 50))
    rgb[:, 0] = 0  # black
    rgb[:, 1] = (0, 0.7, 0)  # pure green
    rgb[:, 2] = (0.3, 0, 0)  # pure red
    model = rgb_to_rho_phi_psi(rgb)
    assert np.allclose(model[0], np.sqrt((rgb**2).sum(0)))
    assert np.allclose(rho_phi_psi_to_rgb(model), rgb, atol=1e-12)


@pytest.mark.parametrize("colour", ["channels", "rho-phi-psi"])
def test_colour_image_with_alpha(colour):
    image = (
        np.stack([_edge_image(32), _edge_image(32, 1.2), 1 - _edge_image(32)], -1) * 255
    ).astype(np.uint8)
    alpha = np.full((32, 32, 1), 200, np.uint8)
    rgba = np.concatenate([image, alpha], -1)
    hole = _disc(32, 16, 16, 4)
    out = clpde.inpaint(rgba, hole, channel_axis=-1, colour=colour)
    assert out.dtype == np.uint8 and out.shape == rgba.shape
    assert np.array_equal(out[..., 3], rgba[..., 3])
    assert np.array_equal(out[~hole], rgba[~hole])
    assert _err(out[..., :3], image, np.repeat(hole[..., None], 3, -1)).mean() < 12


def test_any_number_of_channels_on_any_axis():
    stack = np.stack([_edge_image(24, a) for a in (0.1, 0.7, 1.3, 2.0, 2.9)])  # channels first
    hole = _disc(24, 12, 12, 3)
    out = clpde.inpaint(stack, hole, channel_axis=0)
    assert out.shape == stack.shape
    for c in range(5):
        assert _err(out[c], stack[c], hole).mean() < 0.05


# ---- the contract ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "dtype,scale", [(np.uint8, 255), (np.uint16, 65535), (np.float32, 1), (np.float64, 300)]
)
def test_dtype_preserved_and_bit_exact_outside_the_mask(dtype, scale):
    image = (_edge_image(32) * scale).astype(dtype)
    if dtype == np.float64:
        image = image - 50.0  # any range
    hole = _disc(32, 10, 20, 4)
    before = image.copy()
    out = clpde.inpaint(image, hole.astype(np.uint8) * 7)  # numeric mask: nonzero = inpaint
    assert out.dtype == image.dtype and out is not image
    assert np.array_equal(image, before)  # input untouched
    assert np.array_equal(out[~hole], image[~hole])
    assert _err(out, image, hole).mean() < 0.03 * scale


def test_mask_touching_the_border():
    image = _edge_image(32, angle=0.2)
    hole = np.zeros((32, 32), bool)
    hole[:5, 10:16] = True
    hole[20:26, -4:] = True
    hole[-1, :] = True
    out = clpde.inpaint(image, hole)
    assert np.isfinite(out).all()
    assert _err(out, image, hole).max() < 0.15


def test_empty_mask_returns_a_copy():
    image = np.arange(20, dtype=np.uint8).reshape(4, 5)
    with pytest.warns(UserWarning, match="mask is empty"):
        out = clpde.inpaint(image, np.zeros((4, 5), bool))
    assert np.array_equal(out, image) and out is not image


def test_nan_pixels_are_filled_when_mask_is_none():
    image = _edge_image(32).astype(np.float32) * 10
    holed = image.copy()
    holed[12:16, 8:20] = np.nan
    out = clpde.inpaint(holed, None)
    assert np.isfinite(out).all() and out.dtype == np.float32
    nan = np.isnan(holed)
    assert np.array_equal(out[~nan], holed[~nan])
    assert _err(out, image, nan).mean() < 0.3


def test_snapshots_and_object_form():
    image = _edge_image(32)
    hole = _disc(32, 16, 16, 4)
    out, states = clpde.inpaint(image, hole, snapshots=68, tol=0, max_steps=340)
    steps = [s.step for s in states]
    assert steps[0] == 0 and steps[-1] == 340 and steps == sorted(steps) and len(steps) >= 5
    assert np.array_equal(states[-1].image, out)
    job = Inpainting(image, hole, tol=0, max_steps=68)
    assert [s.step for s in job.iterate(every=34)] == [0, 34, 68, 68]
    assert job.info.steps == 68 and np.array_equal(job.result[~hole], image[~hole])


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"mask": np.zeros((5, 5), bool)}, "does not match"),
        ({"mask": np.ones((8, 8), bool)}, "covers every pixel"),
        ({"mask": np.array([["a"] * 8] * 8)}, "dtype"),
        ({"mask": np.full((8, 8), np.nan)}, "NaN"),
        ({"dt": 0}, "dt"),
        ({"diffusion_dt": 0.5}, "stability"),
        ({"epsilon": 1}, "epsilon"),
        ({"scaling": "cube"}, "scaling"),
        ({"rotation": "left"}, "rotation"),
        ({"colour": "rho-phi-psi"}, "3 colour channels"),
        ({"colour": "lab"}, "colour"),
        ({"levels": 0}, "levels"),
        ({"snapshots": 0}, "snapshots"),
        ({"transport_steps": 0}, "transport_steps"),
        ({"fill": "noise"}, "fill"),
        ({"tol": -1}, "tol"),
        ({"mean_tol": -1}, "mean_tol"),
    ],
)
def test_bad_inputs(kwargs, match):
    image = np.random.default_rng(0).random((8, 8))
    kwargs.setdefault("mask", _disc(8, 4, 4, 2))
    with pytest.raises(clpde.InputError, match=match):
        clpde.inpaint(image, **kwargs)


def test_bad_images():
    mask = np.zeros((8, 8), bool)
    mask[3, 3] = True
    with pytest.raises(clpde.InputError, match="mask=None"):
        clpde.inpaint(np.zeros((8, 8), np.uint8), None)
    with pytest.raises(clpde.InputError, match="dtype complex128"):
        clpde.inpaint(np.zeros((8, 8), complex), mask)  # (bool images are binary ones)
    with pytest.raises(clpde.InputError, match="channel_axis"):
        clpde.inpaint(np.zeros((8, 8, 3)), mask)
    nan = np.zeros((8, 8))
    nan[0, 0] = np.nan
    with pytest.raises(clpde.InputError, match="outside the mask"):
        clpde.inpaint(nan, mask)
    with pytest.raises(clpde.InputError, match="unknown inpainting option"):
        Inpainting(np.zeros((8, 8)), mask, steps=3)


@pytest.mark.parametrize(
    "options",
    [
        {"fill": "biharmonic"},
        {"fill": "zero", "levels": 1},
        {"scaling": "quartic-root"},
        {"keep_band": False},
    ],
)
def test_options_run_and_stay_close(options):
    image = _edge_image(32)
    hole = _disc(32, 16, 16, 4)
    out, info = clpde.inpaint(image, hole, method="transport", return_info=True, **options)
    assert np.array_equal(out[~hole], image[~hole])
    assert _err(out, image, hole).mean() < 0.05 and info.steps > 0
