"""A detected line scratch's profile taken out of the frame (filmfill2, _scratch_fill)."""

import numpy as np
from scipy.ndimage import gaussian_filter, shift

import clpde
from clpde.film._scratch_fill import profile_fill
from clpde.film.detect import SCRATCH


def _textured_pan(rng, T=9, ny=96, nx=80, step=(1.3, 0.2)):
    scene = gaussian_filter(rng.random((ny + 30, nx + 30)), 1.2)
    scene = 0.2 + 0.6 * (scene - scene.min()) / (scene.max() - scene.min())
    frames = [
        shift(scene, (-t * step[0], -t * step[1]), order=3, mode="nearest")[:ny, :nx]
        for t in range(T)
    ]
    grain = 0.01 * rng.standard_normal((T, ny, nx))
    return np.clip(np.stack(frames) + grain, 0, 1).astype(np.float32)


def _scratch(clean, x0=38.0, drift=0.3, width=2.0, strength=0.25):
    """A bright scratch drifting across the frames, a soft Gaussian profile whose strength
    varies slowly along it, laid on the scene as film.py's corpus lays it; the masks are
    twice its width (as the detector's are)."""
    T, ny, nx = clean.shape
    yy, xs = np.arange(ny)[:, None], np.arange(nx)[None, :]
    dirty, masks, core = clean.copy(), np.zeros(clean.shape, bool), np.zeros(clean.shape, bool)
    for t in range(T):
        xc = x0 + drift * t
        along = 1 + 0.3 * np.sin(yy / 20.0)
        a = np.clip(np.exp(-0.5 * ((xs - xc) / (0.5 * width)) ** 2) * along, 0, 1)
        dirty[t] = clean[t] * (1 - a) + a * np.clip(clean[t] + strength, 0, 1)
        masks[t] = np.abs(xs - xc) <= width + 1
        core[t] = a >= 0.2
    return dirty, masks, core


def test_drifting_scratch_over_a_textured_pan_keeps_the_scene(runtime, rng):
    """The scene pans down under a scratch that drifts across with it, so every neighbour
    carries the scratch over the same scene points (flagged) and no neighbour sees them
    clean: before filmfill2 clpde.inpaint guessed across the run, and the texture under it
    was lost.
    Taking out its profile keeps the scene's detail and the frame's grain."""
    clean = _textured_pan(rng)
    dirty, masks, core = _scratch(clean)
    kinds = np.where(masks, SCRATCH, 0).astype(np.int8)
    out = clpde.inpaint_video(dirty, masks, device=runtime, keep=3, kinds=kinds)
    spatial = clpde.inpaint_video(dirty, masks, device=runtime)  # the fill without kinds
    err = np.abs(out - clean)[core]
    err_spatial = np.abs(spatial - clean)[core]
    # the scratch (0.25 at its centre) is gone: 0.024 here (the median of the texture's
    # residual over the rows is the profile's error), main's fill 0.051
    assert err.mean() < 0.03
    # and far closer than the spatial fill's guess across the run (0.050)
    assert err.mean() < 0.6 * err_spatial.mean()
    # the mask beyond the scratch is left nearly as it was (0.006; main 0.016)
    beyond = masks & ~core
    assert np.abs(out - dirty)[beyond].mean() < 0.01


def test_a_deviation_of_the_other_sign_is_left_alone():
    """A bright scratch beside a dark vertical step inside one wide run of the mask: the
    interpolation across the run is a ramp, so the step's pixels deviate from it
    (negative) all along: that is the scene, not the scratch, and keeps its values."""
    ny, nx = 80, 30
    g = np.full((1, ny, nx), 0.6, np.float32)
    g[0, :, 15:] = 0.3  # the step, at column 15
    clean = g.copy()
    g[0, :, 11:13] += 0.2  # the scratch, 2 px, left of the step
    lines = np.zeros((ny, nx), bool)
    lines[:, 9:18] = True  # one run over both
    out, _ = profile_fill(g, lines)
    # the scratch lowered (0.2 -> 0.09 and 0.12: the ramp across the step is the
    # baseline's error there)
    assert np.all(np.abs(out - clean)[0, :, 11:13] < 0.7 * np.abs(g - clean)[0, :, 11:13])
    # the step's dark side, below the ramp: unchanged (subtracting it would lift it)
    np.testing.assert_array_equal(out[0, :, 15:18], g[0, :, 15:18])


def test_a_mask_beside_the_scratch_is_not_mended(rng):
    """A bright scratch whose centre the mask missed, flagged on either side: each run's
    inner flank lies on the scratch, so its interpolation is no baseline (the profile at
    the run's inner end is as large as anywhere). The runs are left as they were (on
    calibration's scan, carphone s6 6, such a baseline changed the scene beside the
    scratch by more than 10 levels over 1.2% of the frame)."""
    ny, nx = 96, 60
    scene = 0.4 + 0.2 * gaussian_filter(rng.random((ny, nx)), 1.0)
    g = (scene + 0.01 * rng.standard_normal((ny, nx)))[None].astype(np.float32)
    xs = np.arange(nx)[None]
    g = g + 0.15 * np.exp(-0.5 * ((xs - 30.0) / 1.5) ** 2)  # the scratch, centred at 30
    lines = np.zeros((ny, nx), bool)
    lines[:, 24:28] = lines[:, 33:37] = True  # the mask, beside it
    out, mended = profile_fill(g, lines)
    assert not mended.any()
    np.testing.assert_array_equal(out, g)
