"""The adaptive discrepancy of clpde.track: kernels/tracking/adaptive.cl against its numpy
reference, the motion per component, the adaptive option and the default on stop-and-go and
split sequences, and the confidence per frame."""

import numpy as np
import pyopencl.array as cla
import pytest
from scipy import ndimage

from clpde.fields import Field, Grid, compact
from clpde.tracking.adaptive import (
    LIGHT_CHANGE,
    ComponentMotion,
    background_change,
    noise_variance,
)
from clpde.tracking.confidence import LOW_CONFIDENCE, track_confidence
from clpde.tracking.options import CURVATURE, REGION_WEIGHT
from clpde.tracking.tracker import MorphingTracker, track
from tests.reference import levelset as ref
from tests.reference import track_adaptive as aref


def _inputs(rng, channels, ny=22, nx=27):
    y, x = np.mgrid[:ny, :nx]
    r = np.hypot(x - 12.3, y - 9.6)
    u = r - 6
    f1 = np.array([1 / (1 + np.exp((r - 6) / 1.5)) * (1 + 0.2 * c) for c in range(channels)])
    r2 = np.hypot(x - 13.5, y - 10.1)
    f2 = np.array([0.6 / (1 + np.exp((r2 - 6.5) / 1.5)) + 0.1 * c for c in range(channels)])
    f1 += 0.05 * rng.normal(size=f1.shape)
    f2 += 0.05 * rng.normal(size=f2.shape)
    return u, f1, f2


@pytest.mark.parametrize(
    "channels,lam,mu,noise2,kd,front_only",
    [
        (1, 0.0, 0.1, 0.004, 1.0, 1),
        (3, 0.1, 0.0, 0.02, 0.5, 1),
        # 2 to 4 channels: summed side by side in 4-vectors' lanes; 5: one after another
        (2, 0.0, 0.1, 0.004, 1.0, 1),
        (4, 0.0, 0.0, 0.02, 1.0, 0),
        (5, 0.0, 0.0, 0.02, 1.0, 1),
        (1, 0.0, 0.2, 1e-6, 0.0, 1),
        (1, 0.0, 0.0, 0.5, 1.0, 0),
    ],
)
def test_morph_adaptive_matches_reference(runtime, rng, channels, lam, mu, noise2, kd, front_only):
    u, f1, f2 = _inputs(rng, channels)
    ny, nx = u.shape
    grid = Grid(runtime, nx, ny, 1, 2, np.dtype(np.float32))
    cgrid = Grid(runtime, nx, ny, channels, 2, np.dtype(np.float32))
    fu = Field.from_host(grid, u[np.newaxis])
    fprior = Field.from_host(grid, (u + rng.normal(size=u.shape))[np.newaxis])
    region = rng.uniform(-0.5, 0.5, u.shape)
    freg = Field.from_host(grid, region[np.newaxis])
    ff1, ff2 = Field.from_host(cgrid, f1), Field.from_host(cgrid, f2)
    band = ref.mark_band(u, 3.0, margin=2)
    padded_band = np.zeros(grid.padded_shape[1:], np.uint8)
    padded_band[2:-2, 2:-2] = band
    band_dev = cla.to_device(runtime.queue, padded_band)
    cells = compact(runtime, band_dev)
    u_out, f1_out = fu.copy(), ff1.copy()
    (gsize,), _, _ = runtime.list_launch(cells.n)
    stats = cla.zeros(runtime.queue, 5 * gsize + 1, np.float32)
    dt, eps_f, eps_u, near, delta = 0.3, 0.02, 1e-3, 1.0, 0.02
    kernel = grid.kernel(
        "tracking/adaptive.cl",
        "adaptive_morph_adaptive",
        NCH=channels,
        WIN=3,
        FRONT_ONLY=front_only,
    )
    grid.launch_list(
        kernel,
        cells,
        fu.data.data,
        ff1.data.data,
        ff2.data.data,
        band_dev.data,
        fprior.data.data,
        u_out.data.data,
        f1_out.data.data,
        stats.data,
        grid.scalar(dt),
        grid.scalar(eps_f**2),
        grid.scalar(eps_u**2),
        grid.scalar(near),
        grid.scalar(lam),
        grid.scalar(delta),
        np.int32(grid.sx),
        np.int32(grid.plane),
        freg.data.data,
        grid.scalar(noise2),
        grid.scalar(mu),
        grid.scalar(kd),
    )
    want_u, want_f1, want_maxima, want_mean, want_hit = aref.morph_adaptive(
        fu.data.get()[0].astype(np.float64),
        ff1.data.get().astype(np.float64),
        ff2.data.get().astype(np.float64),
        band,
        fprior.data.get()[0].astype(np.float64),
        freg.to_host()[0].astype(np.float64),
        dt,
        eps_f,
        eps_u,
        near,
        lam,
        delta,
        noise2,
        mu,
        kd,
        front_only=bool(front_only),
    )
    inside = band > 0
    np.testing.assert_allclose(u_out.to_host()[0][inside], want_u[inside], atol=3e-5, rtol=1e-4)
    np.testing.assert_allclose(
        f1_out.to_host()[:, inside], want_f1[:, inside], atol=3e-5, rtol=1e-4
    )
    got = stats.get()
    maxima = [got[k * gsize : (k + 1) * gsize].max() for k in range(3)]
    np.testing.assert_allclose(maxima, want_maxima, rtol=2e-4, atol=1e-6)
    mean = got[3 * gsize : 4 * gsize].sum() / got[4 * gsize : 5 * gsize].sum()
    np.testing.assert_allclose(mean, want_mean, rtol=2e-4)
    assert bool(got[5 * gsize]) == want_hit


def test_adaptive_beta_is_the_difference_on_flat_patches_and_the_ncc_on_contrast(rng):
    flat1 = ref.pad(0.5 + 0.001 * rng.normal(size=(16, 16)))
    flat2 = ref.pad(0.6 + 0.001 * rng.normal(size=(16, 16)))
    beta = aref.adaptive_beta(flat1, flat2, 0.02, 0.01)
    np.testing.assert_allclose(beta, ref.discrepancy(flat1, flat2, "difference", 0.02), atol=1e-3)
    tex1 = ref.pad(rng.random((16, 16)))
    tex2 = 0.5 * tex1 + 0.3  # a change of light over contrast: the correlation sees nothing
    beta = aref.adaptive_beta(tex1, tex2, 1e-4, 1e-6)
    assert np.abs(beta).max() < 1e-2 < np.abs(tex2 - tex1).mean()


def test_noise_variance_measures_white_noise(rng):
    y, x = np.mgrid[:80, :80]
    smooth = np.sin(x / 9.0) + np.cos(y / 7.0)
    est = noise_variance(smooth + rng.normal(0, 0.1, smooth.shape))
    assert 0.8 * 0.01 < est < 1.2 * 0.01


def _textured_disc(positions, n=64, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[:n, :n] + 0.0
    ground = 0.5 + 0.06 * ndimage.gaussian_filter(rng.normal(size=(n, n)), 1.5) * 3
    tex = ndimage.gaussian_filter(rng.normal(size=(2 * n, 2 * n)), 1.0) * 3
    frames, masks = [], []
    for cx in positions:
        m = np.hypot(y - 32, x - cx) < 10
        obj = 0.7 + 0.06 * ndimage.shift(tex, (0, cx), order=1, mode="wrap")[:n, :n]
        alpha = ndimage.gaussian_filter(m * 1.0, 0.7)
        frames.append(
            np.clip((1 - alpha) * ground + alpha * obj + rng.normal(0, 0.03, (n, n)), 0, 1)
        )
        masks.append(m)
    return np.array(frames), np.array(masks)


def _iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def test_background_change_is_one_under_noise_and_large_under_a_flicker(rng):
    y, x = np.mgrid[:80, :90]
    ground = 0.5 + 0.2 * np.sin(x / 5.0) * np.cos(y / 7.0)
    mask = np.hypot(y - 40, x - 45) < 12
    sigma = 0.04
    before = ground + rng.normal(0, sigma, ground.shape)
    after = ground + rng.normal(0, sigma, ground.shape)
    after[mask] += 0.3  # the object changes; it is left out
    # two frames of white noise differ by 2 sigma / sqrt(pi) on average
    assert abs(background_change(before, after, mask, sigma**2) - 1) < 0.05
    flicker = 1.5 * after + 0.1
    assert background_change(before, flicker, mask, sigma**2) > LIGHT_CHANGE
    # the object's surroundings (8 px) are left out with it
    near = ndimage.binary_dilation(mask, iterations=8) & ~mask
    moved = after.copy()
    moved[near] += 0.5
    assert abs(background_change(before, moved, mask, sigma**2) - 1) < 0.05


def test_component_motion_stops_with_the_object():
    positions = [16, 19, 22, 22, 22]
    frames, masks = _textured_disc(positions)
    motion = ComponentMotion(6)
    got = [
        motion.predict(frames[k][None], frames[k + 1][None], masks[k])[0][1][1]
        for k in range(len(frames) - 1)
    ]
    assert abs(got[0] - 3) < 0.5 and abs(got[1] - 3) < 0.5
    assert got[2] == 0.0 and got[3] == 0.0  # no overshoot once it stops


# The adaptive option: motion per piece, the adaptive discrepancy, region and curvature terms.
ADAPTIVE = {
    "motion": "components",
    "discrepancy": "adaptive",
    "region_weight": REGION_WEIGHT,
    "curvature": CURVATURE,
}


@pytest.mark.parametrize("options", [ADAPTIVE, {}], ids=["adaptive option", "default"])
def test_adaptive_tracks_stop_and_go(options):
    positions = [16, 18, 21, 25, 25, 25, 20.5, 16, 11.5 + 4.5]
    frames, truth = _textured_disc(positions)
    masks = track(frames, truth[0], **options)
    scores = [_iou(m, t) for m, t in zip(masks[1:], truth[1:], strict=True)]
    assert min(scores) > 0.75, scores
    assert np.mean(scores) > 0.85, scores


@pytest.mark.parametrize("options", [ADAPTIVE, {}], ids=["adaptive option", "default"])
def test_adaptive_tracks_a_split(options):
    y, x = np.mgrid[:64, :64] + 0.0
    rng = np.random.default_rng(1)
    frames, truth = [], []
    for t in range(7):
        s = t / 6
        d, w = 9 + 4 * s, 4.5 - 7 * s
        m = (np.hypot(x - 32 + d, y - 32) < 10) | (np.hypot(x - 32 - d, y - 32) < 10)
        m |= (np.abs(y - 32) < w) & (np.abs(x - 32) < d)
        img = ndimage.gaussian_filter(0.3 + 0.4 * m, 1.0) + rng.normal(0, 0.06, m.shape)
        frames.append(np.clip(img, 0, 1))
        truth.append(m)
    masks = track(np.array(frames), truth[0], **options)
    scores = [_iou(m, t) for m, t in zip(masks[1:], truth[1:], strict=True)]
    assert min(scores) > 0.8, scores
    assert ndimage.label(masks[-1])[1] == 2


def test_confidence_flags_a_lost_track_and_not_a_clean_one():
    positions = [16 + 2 * t for t in range(9)]
    frames, truth = _textured_disc(positions)
    masks, conf = track(frames, truth[0], return_confidence=True)
    assert conf.shape == (len(frames),) and conf[0] == 1.0
    assert ((0 <= conf) & (conf <= 1)).all()
    assert (conf[1:] >= LOW_CONFIDENCE).all(), conf
    lost = truth.copy()
    lost[4:] = np.roll(truth[4:], 22, axis=1)  # from frame 4 on, the contour is elsewhere
    lost[4:] = np.roll(lost[4:], 18, axis=2)
    bad = track_confidence(frames, lost)
    assert (bad[4:] < LOW_CONFIDENCE).all(), bad


def test_return_confidence_with_the_tracker_and_other_outputs():
    frames, truth = _textured_disc([16, 18, 20])
    tracker = MorphingTracker(frames, truth[0])
    conf = tracker.confidence([s.mask for s in tracker.iterate()])
    assert conf.shape == (3,)
    masks, levels, residuals, conf2 = track(
        frames, truth[0], return_level_sets=True, return_discrepancy=True, return_confidence=True
    )
    assert levels.shape == masks.shape and residuals.shape == conf2.shape == (3,)
