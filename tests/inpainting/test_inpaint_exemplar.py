"""Exemplar inpainting (clpde.inpainting.exemplar): kernels against their NumPy references
(tests/reference/patchmatch.py), and the method against what it must do exactly."""

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.inpainting import exemplar, patchmatch
from tests.reference import patchmatch as ref


def _level(
    runtime, seed=0, patch=5, shape=(21, 26), nch=3, dtype=np.float32, nout=None, confidence=1.0
):
    rng = np.random.default_rng(seed)
    img = rng.random((nch,) + shape)
    hole = np.zeros(shape, bool)
    hole[6:12, 8:15] = True
    hole[15:, 20:] = True  # touches two borders: clipped target patches
    weights = rng.uniform(0.5, 2.0, nch)
    lv = patchmatch.PatchMatchLevel(
        runtime, dtype, img, hole, weights, patch, nout, confidence=confidence
    )
    lv.random_nnf(rng)
    return lv, img, hole, weights


def _score(lv, hole, masked, seed):
    """Score the level's field (pm_score), with a random 70% of the known pixels usable if
    masked; the mask used (None: all)."""
    use = None
    if masked:
        use = ~hole & (np.random.default_rng(seed).random(hole.shape) < 0.7)
        lv.d_use.set(use.astype(np.uint8).ravel())
    lv._launch(
        lv.k_score,
        lv.targets[1],
        lv.img.data,
        lv.d_use.data,
        np.int32(masked),
        lv.nnf[0].data,
        lv.dist.data,
        lv.targets[0].data,
        np.int32(lv.targets[1]),
        *lv._args(),
    )
    return use


@pytest.mark.parametrize("masked", [False, True])
def test_patch_distance_matches_reference(runtime, masked):
    lv, img, hole, w = _level(runtime)
    use = _score(lv, hole, masked, seed=1)
    got = lv.dist.get().reshape(hole.shape)
    want = ref.distances(img, w, lv.nnf_to_host(), lv.targets_mask, lv.r, use)
    finite = np.isfinite(want)
    assert np.array_equal(finite, np.isfinite(got))
    np.testing.assert_allclose(got[finite], want[finite], rtol=2e-5, atol=1e-7)


@pytest.mark.parametrize(
    "best_only,nout,confidence",
    [(False, None, 1.0), (True, None, 1.0), (False, 2, 1.0), (False, None, 1.3), (True, None, 2.0)],
)
def test_vote_matches_reference(runtime, best_only, nout, confidence):
    lv, img, hole, w = _level(runtime, seed=3, nout=nout, confidence=confidence)
    lv.score()
    nnf, dist = lv.nnf_to_host(), lv.dist.get().reshape(hole.shape)
    lv.vote(best_only=best_only, sigma2=0.05)
    got = lv.image()
    # The confidence penalty: depth into the hole (Euclidean) times log(confidence).
    from scipy import ndimage

    pen = ndimage.distance_transform_edt(hole) * np.log(confidence)
    want = ref.vote(img, nnf, dist, hole, lv.r, 0.05, best_only, nout, pen)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)
    assert np.array_equal(got[:, ~hole], img[:, ~hole].astype(np.float32))


def test_patchmatch_pass_never_worsens_and_stays_legal(runtime):
    lv, img, hole, w = _level(runtime, seed=5)
    lv.score()
    before = lv.dist.get()[lv.targets_idx]
    lv.patchmatch(3, lv.targets, False, seed=0, counter=[0])
    after = lv.dist.get()[lv.targets_idx]
    assert np.all(after <= before * (1 + 1e-6))
    assert after.mean() < 0.9 * before.mean()
    src = lv.nnf_to_host().reshape(-1, 2)[lv.targets_idx]
    assert lv.valid[src[:, 1], src[:, 0]].all()


def test_coherence_matches_reference(runtime):
    lv, img, hole, w = _level(runtime, seed=7)
    lv.score()
    nnf, dist = lv.nnf_to_host(), lv.dist.get().reshape(hole.shape)
    lv.cohere(2, 1.5)
    want_nnf, want_dist = ref.cohere(img, w, nnf, dist, lv.valid, lv.targets_mask, lv.r, 1.5, 2)
    got = lv.nnf_to_host()
    assert (got != nnf).any(2).sum() > 20  # the sweeps did move offsets
    assert np.array_equal(got, want_nnf)
    np.testing.assert_allclose(
        lv.dist.get().reshape(hole.shape)[lv.targets_mask],
        want_dist[lv.targets_mask],
        rtol=2e-5,
        atol=1e-7,
    )


def _distinct_offsets(lv):
    off = lv.nnf_to_host() - np.stack(np.meshgrid(np.arange(lv.W), np.arange(lv.H)), -1)
    return len(np.unique(off[lv.hole], axis=0))


def test_coherence_joins_equally_good_copies(runtime):
    # Stripes with a little noise: every source of the right phase is nearly as good, so
    # PatchMatch leaves a patchwork of them; the sweeps must join it into fewer regions.
    rng = np.random.default_rng(0)
    x = np.arange(64)
    img = (0.5 + 0.4 * np.sin(2 * np.pi * x / 8))[None, None, :].repeat(64, 1)
    img = img + 0.01 * rng.standard_normal((1, 64, 64))
    hole = np.zeros((64, 64), bool)
    hole[24:40, 24:40] = True
    lv = patchmatch.PatchMatchLevel(runtime, np.float32, img, hole, [1.0], 5)
    lv.random_nnf(rng)
    lv.score()
    lv.patchmatch(6, lv.targets, False, seed=0, counter=[0])
    before = _distinct_offsets(lv)
    d0 = lv.dist.get()[lv.targets_idx]
    lv.cohere(4, 1.5)
    assert _distinct_offsets(lv) < 0.5 * before
    # each pixel gave up at most a factor 1.5**8 of its distance, most far less
    assert lv.dist.get()[lv.targets_idx].mean() < 2 * d0.mean()


@pytest.mark.parametrize("masked", [False, True])
def test_try_offsets_matches_reference(runtime, masked):
    lv, img, hole, w = _level(runtime, seed=7, nout=2)  # plane 2 plays a texture feature
    lv.ncolour = 2
    img[:2] = np.tile(img[:2, :, :5], (1, 1, 6))[:, :, : img.shape[2]]  # colours repeat by 5
    lv.img.set(img.astype(np.float32))
    use = _score(lv, hole, masked, seed=2)
    nnf, dist = lv.nnf_to_host(), lv.dist.get().reshape(hole.shape)
    lags = np.array([[5, 0], [-5, 0], [10, 0], [-10, 0], [3, 2], [0, -4]], np.int32)
    lv.try_offsets(cla.to_device(lv.q, lags), masked=masked)
    want_nnf, want_dist = ref.try_offsets(
        img.astype(np.float32),
        w,
        [w[0], w[1], 0],
        nnf,
        dist,
        lv.targets_mask,
        lv.valid,
        lags,
        lv.r,
        use,
    )
    assert np.array_equal(lv.nnf_to_host(), want_nnf)
    got = lv.dist.get().reshape(hole.shape)
    finite = np.isfinite(want_dist)
    np.testing.assert_allclose(got[finite], want_dist[finite], rtol=2e-5, atol=1e-7)
    assert (want_nnf != nnf).any()  # some targets moved to a repeat of their colours


def _grid(n=192):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    img = (0.3 + 0.5 * ((x % 23 < 3) | (y % 23 < 3)))[None]  # 3 px lines, period 23
    omega = (y - 36) ** 2 + (x - 163) ** 2 <= 20**2
    omega |= (y - 124) ** 2 + (x - 31) ** 2 <= 7.5**2
    omega |= (abs(y - 147) <= 12) & (abs(x - 57) <= 12)
    return img, omega


def test_periodic_pattern_exact_at_every_seed(runtime):
    # Between the lines a patch is flat and matches any phase; without the lattice's lags
    # the field kept a wrong one at every seed (the holes of benchmarks/exemplar_seeds.py's
    # grid23; docs/inpainting_texture.md has the figures).
    img, omega = _grid()
    for seed in range(5):
        out = exemplar.solve(img, omega, runtime, seed=seed)
        assert _psnr(out, img, omega) > 45, seed


def _periodic(n=112):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    return np.stack(
        [
            0.5 + 0.4 * np.sin(2 * np.pi * x / 12) * np.cos(2 * np.pi * y / 16),
            0.5 + 0.3 * np.sin(2 * np.pi * (x / 12 + y / 16)),
            0.3 + 0.4 * ((x // 6 + y // 8) % 2),
        ]
    )


def _psnr(a, b, mask):
    mse = np.mean((a[:, mask] - b[:, mask]) ** 2)
    return np.inf if mse == 0 else 10 * np.log10(1 / mse)


def test_periodic_pattern_comes_back(runtime):
    img = _periodic()
    omega = np.zeros(img.shape[1:], bool)
    omega[30:62, 40:70] = True  # 32 x 30: two pyramid levels
    out = exemplar.solve(img, omega, runtime, seed=0)
    assert _psnr(out, img, omega) > 35
    assert np.array_equal(out[:, ~omega], img[:, ~omega])
    assert out.dtype == img.dtype and out.shape == img.shape


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_constant_image_gives_the_constant(runtime, dtype):
    if dtype == np.float64 and not runtime.fp64:
        pytest.skip("the device has no double precision")
    img = np.full((1, 60, 70), 0.3)
    omega = np.zeros((60, 70), bool)
    omega[10:40, 20:50] = True
    out = exemplar.solve(img, omega, runtime, dtype=dtype)
    np.testing.assert_allclose(out, 0.3, atol=1e-6 if dtype == np.float32 else 1e-14)


def test_values_in_the_hole_are_not_read(runtime):
    img = _periodic(64)
    omega = np.zeros(img.shape[1:], bool)
    omega[20:40, 24:44] = True
    a, b = img.copy(), img.copy()
    a[:, omega] = np.nan
    b[:, omega] = 0.9
    out = exemplar.solve(a, omega, runtime, seed=3)
    assert np.isfinite(out).all()
    assert np.array_equal(out, exemplar.solve(b, omega, runtime, seed=3))


@pytest.mark.parametrize("structure", [None, 0.0, 1.0])
def test_same_seed_same_result(runtime, structure):
    rng = np.random.default_rng(2)
    img = np.clip(0.5 + 0.2 * rng.standard_normal((3, 64, 64)), 0, 1)
    omega = np.zeros((64, 64), bool)
    omega[20:44, 18:40] = True
    a = exemplar.solve(img, omega, runtime, seed=7, structure=structure)
    b = exemplar.solve(img, omega, runtime, seed=7, structure=structure)
    c = exemplar.solve(img, omega, runtime, seed=8, structure=structure)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_hole_touching_two_borders(runtime):
    img = _periodic(96)
    omega = np.zeros(img.shape[1:], bool)
    omega[:20, -24:] = True  # the top right corner
    omega[70:, :10] = True  # and the bottom left one
    out = exemplar.solve(img, omega, runtime, seed=0)
    assert _psnr(out, img, omega) > 35
    assert np.array_equal(out[:, ~omega], img[:, ~omega])


def test_bad_parameters_are_clear_errors(runtime):
    from clpde import InputError

    img = np.zeros((1, 20, 20))
    omega = np.zeros((20, 20), bool)
    omega[5:8, 5:8] = True
    with pytest.raises(InputError, match="patch must be an odd"):
        exemplar.solve(img, omega, runtime, patch=4)
    with pytest.raises(InputError, match="iterations must be"):
        exemplar.solve(img, omega, runtime, iterations=0)
    with pytest.raises(InputError, match="confidence must be"):
        exemplar.solve(img, omega, runtime, confidence=0.5)
    with pytest.raises(InputError, match="structure must be"):
        exemplar.solve(img, omega, runtime, structure=-1)
    with pytest.raises(InputError, match="whole image"):
        exemplar.solve(img, np.ones((20, 20), bool), runtime)


def test_levels_follow_the_hole_thickness_not_a_few_crossings():
    # Thin strokes (3 px) that cross: one level, however deep the few crossing pixels are.
    thin = np.zeros((200, 200), bool)
    for k in range(20, 180, 12):
        thin[k : k + 3, 10:190] = True
        thin[10:190, k : k + 3] = True
    thin[100:108, 100:108] = True  # one small blob, deeper than the strokes
    assert exemplar._levels_for(thin, 3, thin.shape) == 1
    thick = np.zeros((300, 300), bool)
    thick[100:180, 100:180] = True  # 80 px: half-thickness 40, down to ~3 in 4 levels
    assert exemplar._levels_for(thick, 3, thick.shape) == 4
