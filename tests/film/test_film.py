"""Film restoration: the detector and fill kernels against their numpy references, and
detect_defects / inpaint_video on small synthetic sequences."""

import numpy as np
import pyopencl.array as cla
import pytest
from scipy.ndimage import gaussian_filter, shift

import clpde
from clpde import InputError
from clpde.film import BLOTCH, SCRATCH
from tests.reference import film as ref


def _dev(q, a, dtype=np.float32):
    return cla.to_device(q, np.ascontiguousarray(a, dtype))


def _scene(rng, ny=160, nx=200, sigma=2.0):
    s = gaussian_filter(rng.random((ny, nx)), sigma)
    return (s - s.min()) / (s.max() - s.min())


def _pan(scene, T, step=(0.6, 1.7), ny=64, nx=80, rng=None, grain=0.0):
    """T frames of a camera panning over scene: frame t at offset t * step (sub-pixel)."""
    frames = []
    for t in range(T):
        f = shift(scene, (-t * step[0], -t * step[1]), order=3, mode="nearest")[:ny, :nx]
        if grain:
            f = f + grain * rng.standard_normal(f.shape)
        frames.append(f)
    return np.clip(np.stack(frames), 0, 1).astype(np.float32)


# ---- kernels against references --------------------------------------------------------------
def test_blotch_kernel_matches_reference(runtime, rng):
    from clpde.film.detect import _Kernels

    kern = _Kernels(runtime)
    q = runtime.queue
    ny, nx, K = 9, 13, 4
    I = rng.random((ny, nx))  # noqa: E741 (the kernel's name for the frame)
    W = rng.random((K, ny, nx))
    V = (rng.random((K, ny, nx)) > 0.25).astype(float)
    gain = np.array([1.1, 0.9, 1.0, 1.05])
    offset = np.array([0.01, -0.02, 0.0, 0.03])
    side = np.array([-1, -1, 1, 1], np.int32)
    outs = [cla.empty(q, (ny, nx), np.float32) for _ in range(5)]
    g, loc = runtime.items(nx, ny)
    kern.blotch(
        q,
        g,
        loc,
        _dev(q, I).data,
        _dev(q, W).data,
        _dev(q, V).data,
        _dev(q, gain).data,
        _dev(q, offset).data,
        _dev(q, side, np.int32).data,
        np.int32(K),
        np.float32(0.05),
        np.float32(0.5),
        *(o.data for o in outs),
        np.int32(nx),
        np.int32(ny),
    )
    want = ref.blotch_score(I, W, V, gain, offset, side, 0.05, 0.5)
    for got, exp in zip(outs, want, strict=True):
        np.testing.assert_allclose(got.get(), exp, atol=2e-5)


def test_line_kernels_match_reference(runtime, rng):
    from clpde.film.detect import _Kernels

    kern = _Kernels(runtime)
    q = runtime.queue
    ny, nx = 21, 17
    src = rng.normal(size=(ny, nx))
    g, loc = runtime.items(nx, ny)
    col = cla.empty(q, (ny, nx), np.float32)
    kern.colmean(
        q,
        g,
        loc,
        _dev(q, src).data,
        col.data,
        np.int32(4),
        np.float32(1.5),
        np.int32(nx),
        np.int32(ny),
    )
    np.testing.assert_allclose(col.get(), ref.column_mean(src, 4, 1.5), atol=1e-5)
    line = cla.empty(q, (ny, nx), np.float32)
    kern.line(q, g, loc, _dev(q, src).data, line.data, np.int32(3), np.int32(nx), np.int32(ny))
    np.testing.assert_allclose(line.get(), ref.line_response(src, 3), atol=1e-5)
    box = cla.empty(q, (ny, nx), np.float32)
    kern.box(q, g, loc, _dev(q, src).data, box.data, np.int32(2), np.int32(nx), np.int32(ny))
    np.testing.assert_allclose(box.get(), ref.box_mean(src, 2), atol=1e-5)
    zs = rng.normal(size=(3, ny, nx)).astype(np.float32)
    got = kern.continuity(zs)
    for t in range(3):
        want = ref.scratch_continuity(zs[max(t - 1, 0)], zs[t], zs[min(t + 1, 2)], t > 0, t < 2)
        np.testing.assert_allclose(got[t], want, atol=1e-5)


def test_fill_kernel_matches_reference(runtime, rng):
    q = runtime.queue
    k_fill = runtime.kernel("film/fill.cl", "fill_temporal")
    C, ny, nx, K = 2, 11, 14, 3
    F = rng.random((C, ny, nx))
    G = F.mean(0)
    M = np.zeros((ny, nx))
    M[3:8, 4:9] = 1.0
    M[5, 10] = 0.5
    W = F[None] + 0.05 * rng.normal(size=(K, C, ny, nx))
    Wg = W.mean(1)
    MW = np.zeros((K, ny, nx))
    MW[0, 4:6, 5:7] = 1.0
    V = np.ones((K, ny, nx))
    V[2, :, :3] = 0
    V[:, 7, 8] = 0  # seen by no neighbour
    gain, offset = np.array([1.0, 1.1, 0.9]), np.array([0.0, -0.05, 0.05])
    dist = np.array([1.0, 1.5, 2.0])
    out = cla.empty(q, (C, ny, nx), np.float32)
    left = cla.empty(q, (ny, nx), np.float32)
    g, loc = runtime.items(nx, ny)
    k_fill(
        q,
        g,
        loc,
        *(_dev(q, a).data for a in (F, G, M, W, Wg, MW, V, gain, offset, dist)),
        np.int32(K),
        np.int32(C),
        np.float32(0.02),
        np.int32(2),
        np.float32(0.01),
        out.data,
        left.data,
        np.int32(nx),
        np.int32(ny),
    )
    want, unfilled = ref.temporal_fill(F, G, M, W, Wg, MW, V, gain, offset, dist, 0.02, 2, 0.01)
    np.testing.assert_allclose(out.get(), want, atol=1e-5)
    np.testing.assert_array_equal(left.get(), unfilled)
    assert unfilled[7, 8] == 1


# ---- detection -------------------------------------------------------------------------------
def _blotches(frames, rng, per_frame=3, value=None):
    """Square-ish dark or bright blotches on every frame; returns (dirty, truth)."""
    dirty = frames.copy()
    truth = np.zeros(frames.shape, bool)
    T, ny, nx = frames.shape
    for t in range(T):
        for _ in range(per_frame):
            r = int(rng.integers(2, 5))
            y, x = int(rng.integers(8, ny - 8)), int(rng.integers(8, nx - 8))
            yy, xx = np.mgrid[0:ny, 0:nx]
            blob = np.hypot(yy - y, xx - x) <= r
            dirty[t][blob] = rng.choice([0.0, 1.0]) if value is None else value
            truth[t] |= blob
    # damage that changes a pixel by less than 0.1 (dark dirt on a dark place) is not sought
    return dirty, truth & (np.abs(dirty - frames) > 0.1)


@pytest.mark.parametrize("step", [(0.0, 0.0), (0.6, 1.7)], ids=["static", "pan"])
def test_blotches_found(runtime, rng, step):
    frames = _pan(_scene(rng), 6, step=step, rng=rng, grain=0.01)
    dirty, truth = _blotches(frames, rng)
    # the default threshold is 7 noise units (chosen on real footage's calibration half):
    # blotches that stand out of this grain (0.01) by 20 deviations are all to be found
    truth &= np.abs(dirty - frames) > 0.2
    mask, kinds = clpde.detect_defects(dirty, return_kinds=True, device=runtime)
    assert mask.shape == dirty.shape and mask.dtype == bool
    hit = (kinds == BLOTCH) & truth
    # 0.89 on the pan: the guards of do-no-harm drop a blotch whose flow is disturbed
    assert hit.sum() >= 0.85 * truth.sum()
    # 0.30 on the static scene (0.23 before the grain's range allowance of issue 34 lowered
    # the scale where 4 neighbours spread as grain does, 0.26 before the rim growth of
    # clpde/film/_grow.py: a hard-edged disc has no rim, and the clean pixels around it
    # join at the rim test's rate, the frame's top 5% of residuals): clean pixels beside
    # these hard-edged discs, whose flow the discs disturb
    assert (mask & ~truth).sum() <= 0.32 * truth.sum()


def test_fast_object_is_not_a_blotch(runtime, rng):
    """A textured disc crossing a static scene at 9 px per frame: the flow misses it, but
    it reappears displaced in the neighbours, so it is not dirt."""
    scene = _pan(_scene(rng), 6, step=(0.0, 0.0), rng=rng, grain=0.005)
    patch = _scene(rng, 21, 21, 1.0)
    yy, xx = np.mgrid[-10:11, -10:11]
    disc = np.hypot(yy, xx) <= 9.5
    frames = scene.copy()
    obj = np.zeros(frames.shape, bool)
    for t in range(6):
        y, x = 30, 14 + 9 * t
        region = frames[t, y - 10 : y + 11, x - 10 : x + 11]
        region[disc] = patch[disc]
        obj[t, y - 10 : y + 11, x - 10 : x + 11] = disc
    mask = clpde.detect_defects(frames, device=runtime)
    assert (mask & obj).sum() <= 0.05 * obj.sum()


def test_scratch_found_and_scene_lines_not(runtime, rng):
    """A panning scene with real vertical lines, and a dark scratch fixed on the film."""
    scene = _scene(rng, 160, 240)
    scene[:, ::17] = 0.95  # poles in the scene, moving with the camera
    frames = _pan(scene, 6, step=(0.0, 2.0), ny=72, nx=96, rng=rng, grain=0.01)
    dirty = frames.copy()
    dirty[:, 5:68, 50] = 0.05
    truth = np.zeros(frames.shape, bool)
    truth[:, 5:68, 50] = True
    mask, kinds = clpde.detect_defects(dirty, return_kinds=True, device=runtime)
    assert ((kinds == SCRATCH) & truth).sum() >= 0.8 * truth.sum()
    away = np.ones(truth.shape, bool)
    away[:, :, 48:53] = False  # the scratch and its rim
    assert (mask & away).sum() <= 0.1 * truth.sum()  # the poles are not scratches


def test_static_pole_is_not_a_scratch(runtime, rng):
    """A still shot: a pole standing in the scene, and a thin dark line that stays in place
    in every frame; neither is taken for damage (a line that never moves against the scene
    cannot be told from the scene: the static-line detector is off, do no harm)."""
    scene = _scene(rng, 72, 96, sigma=3.0) * 0.5 + 0.25
    scene[:, 20:26] = 0.9
    scene[6:66, 60] = 0.05
    frames = np.clip(scene + 0.01 * rng.standard_normal((6, 72, 96)), 0, 1).astype(np.float32)
    mask = clpde.detect_defects(frames, device=runtime)
    assert not mask[:, :, 17:29].any() and not mask[:, :, 57:64].any()


@pytest.mark.xfail(
    strict=True,
    reason="a scratch that never moves, of one shade, in a still shot is a post to the eye and "
    "to film_scratches: left alone (do no harm; test_static_pole_is_not_a_scratch)",
)
def test_static_scratch_found_and_static_pole_not(runtime, rng):
    """A still shot (grain only): a thin dark scratch that stays in place is found by its
    own line in each frame; a pole (wider than a scratch) standing in the scene is not."""
    scene = _scene(rng, 72, 96, sigma=3.0) * 0.5 + 0.25
    scene[:, 20:26] = 0.9  # the pole, 6 px wide, in every frame at the same place
    T = 6
    frames = np.clip(scene + 0.01 * rng.standard_normal((T, 72, 96)), 0, 1).astype(np.float32)
    dirty = frames.copy()
    dirty[:, 6:66, 60] = 0.05
    truth = np.zeros(frames.shape, bool)
    truth[:, 6:66, 60] = True
    mask, kinds = clpde.detect_defects(dirty, return_kinds=True, device=runtime)
    assert ((kinds == SCRATCH) & truth).sum() >= 0.8 * truth.sum()
    assert not mask[:, :, 17:29].any()  # the pole and its edges
    away = np.ones(truth.shape, bool)
    away[:, :, 58:63] = False
    assert (mask & away).sum() <= 0.05 * truth.sum()


def test_single_photo_specks_and_scratch(runtime, rng):
    photo = gaussian_filter(rng.random((96, 96)), 4)
    photo = (photo - photo.min()) / (photo.max() - photo.min()) * 0.6 + 0.2
    photo += 0.005 * rng.standard_normal(photo.shape)
    dirty = photo.copy()
    dirty[20:23, 30:33] = 0.95  # a speck
    dirty[60:62, 70:72] = 0.02  # another
    dirty[10:90, 45] = 0.95  # a scratch
    mask, kinds = clpde.detect_defects(dirty, return_kinds=True, device=runtime)
    assert mask.shape == photo.shape
    assert kinds[20:23, 30:33].min() == BLOTCH and kinds[60:62, 70:72].min() == BLOTCH
    assert (kinds[10:90, 45] == SCRATCH).mean() > 0.8
    assert mask.mean() < 0.1


def test_grow_and_dtype(runtime, rng):
    frames = (_pan(_scene(rng), 5, rng=rng, grain=0.01) * 255).astype(np.uint8)
    dirty = frames.copy()
    dirty[2, 30:34, 40:44] = 255
    m0 = clpde.detect_defects(dirty, device=runtime)
    m2, k2 = clpde.detect_defects(dirty, grow=2, return_kinds=True, device=runtime)
    assert m0[2, 30:34, 40:44].all()
    assert m2.sum() > m0.sum() and (m2 >= m0).all()
    assert (k2[m2] > 0).all()
    assert np.array_equal(dirty[:2], frames[:2])  # input untouched


# ---- filling ---------------------------------------------------------------------------------
def test_temporal_fill_restores_a_translated_sequence(runtime, rng):
    clean = _pan(_scene(rng), 7, step=(0.8, 2.3))
    dirty, truth = _blotches(clean, rng, per_frame=2)
    dirty[:, 10:60, 37:39] = 1.0  # a scratch fixed on the film, seen clean by neighbours
    truth[:, 10:60, 37:39] = True
    out, unfilled = clpde.inpaint_video(dirty, truth, device=runtime, return_unfilled=True)
    assert out.dtype == dirty.dtype and out.shape == dirty.shape
    seen = truth & ~unfilled
    seen[:, :6] = seen[:, -6:] = False  # rows and columns the pan brings in from outside
    seen[:, :, :8] = seen[:, :, -8:] = False
    err = np.abs(out - clean)[seen]
    assert np.median(err) < 0.01 and np.percentile(err, 95) < 0.04
    np.testing.assert_array_equal(out[~truth], dirty[~truth])  # clean pixels stay


def test_fill_colour_and_soft_masks(runtime, rng):
    base = _pan(_scene(rng), 5, step=(0.0, 1.5))
    clean = (np.stack([base, base**2, 1 - base], axis=-1) * 65535).astype(np.uint16)
    dirty = clean.copy()
    dirty[2, 20:30, 30:40] = 0
    soft = np.zeros(base.shape, np.float32)
    soft[2, 20:30, 30:40] = 1.0
    soft[2, 19, 30:40] = 0.5
    out = clpde.inpaint_video(dirty, soft, channel_axis=-1, device=runtime)
    assert out.dtype == np.uint16 and out.shape == clean.shape
    err = np.abs(out[2, 20:30, 30:40].astype(int) - clean[2, 20:30, 30:40].astype(int))
    assert np.median(err) < 0.01 * 65535


def test_spatial_fallback_keeps_grain(runtime, rng):
    """A blotch at the same place in every frame of a static shot: no neighbour sees it, so
    the spatial fill takes it, with grain."""
    base = np.full((5, 48, 48), 0.5, np.float32) + 0.03 * rng.standard_normal((5, 48, 48))
    base = base.astype(np.float32)
    masks = np.zeros(base.shape, bool)
    masks[:, 16:32, 16:32] = True
    dirty = base.copy()
    dirty[masks] = 0.0
    out, unfilled = clpde.inpaint_video(dirty, masks, device=runtime, return_unfilled=True)
    assert unfilled[:, 16:32, 16:32].all()
    filled = out[:, 18:30, 18:30]
    assert abs(filled.mean() - 0.5) < 0.03
    assert filled.std() > 0.015  # grain, not a smooth patch


def test_bad_input(runtime):
    frames = np.zeros((4, 32, 32), np.float32)
    with pytest.raises(InputError, match="masks for 4 frames"):
        clpde.inpaint_video(frames, np.zeros((3, 32, 32), bool))
    with pytest.raises(InputError, match="shape"):
        clpde.inpaint_video(frames, np.zeros((4, 32, 30), bool))
    with pytest.raises(InputError, match="float masks"):
        clpde.inpaint_video(frames, np.full((4, 32, 32), 2.0))
    with pytest.raises(InputError, match="grow"):
        clpde.detect_defects(frames, grow=-1)
    with pytest.raises(InputError, match="channel_axis"):
        clpde.detect_defects(np.zeros((2, 3, 32, 32)))
    with pytest.raises(InputError):
        clpde.detect_defects(np.zeros((4, 32, 32), complex))


def test_the_self_check_refuses_a_repair_the_residual_does_not_explain():
    """Two regions under the mask: a blotch (the frame is 0.3 off its neighbours, the repair
    takes it back) is kept; a false alarm (the frame matches its neighbours within the
    grain, the repair moves it by 0.1) is refused; a region without a trusted neighbour
    may change by the noise only."""
    from clpde.film.fill import _self_check

    rng = np.random.default_rng(0)
    sigma = 0.01
    frame = 0.5 + sigma * rng.standard_normal((40, 60))
    hole = np.zeros((40, 60), bool)
    hole[5:12, 5:12] = hole[5:12, 30:37] = hole[25:32, 5:12] = True
    resid2 = 2 * sigma**2 * rng.chisquare(1, frame.shape)  # grain only
    frame[5:12, 5:12] += 0.3  # the blotch
    resid2[5:12, 5:12] = (0.3 + sigma * rng.standard_normal((7, 7))) ** 2
    resid2[25:32, 5:12] = np.inf  # no trusted neighbour
    restored = frame.copy()
    restored[5:12, 5:12] -= 0.3
    restored[5:12, 30:37] += 0.1
    restored[25:32, 5:12] += 0.005
    refused = _self_check(restored, frame, hole, resid2, sigma)
    assert not refused[5:12, 5:12].any() and not refused[25:32, 5:12].any()
    assert refused[5:12, 30:37].all() and refused.sum() == 49


def test_order_statistics_match_a_sort(rng):
    """The sorting network's median and the two least magnitudes against np.sort and a
    stable argsort, with untrusted neighbours, ties and pixels with none trusted."""
    from clpde.film._order import median, second_least

    for K in (1, 2, 3, 4, 5):
        vals = rng.random((K, 20, 30)).astype(np.float32)
        vals[:, :4] = 0.5  # ties
        ok = rng.random((K, 20, 30)) < 0.7
        v = rng.random((20, 30)).astype(np.float32)
        s = np.sort(np.where(ok, vals, np.inf), axis=0)
        n = ok.sum(0)
        lo = np.take_along_axis(s, np.maximum((n - 1) // 2, 0)[None], 0)[0]
        hi = np.take_along_axis(s, np.maximum(n // 2, 0)[None], 0)[0]
        expected = np.where(n > 0, 0.5 * (lo + hi), np.nan).astype(np.float32)
        assert np.array_equal(median(vals, ok), expected, equal_nan=True)
        d = np.where(ok, v[None] - vals, np.inf)
        order = np.argsort(np.abs(d), axis=0, kind="stable")
        first = np.take_along_axis(d, order[:1], 0)[0]
        second = np.take_along_axis(d, order[1:2], 0)[0] if K > 1 else first
        least = np.where(n > 0, np.where(n >= 3, second, first), 0.0).astype(np.float32)
        assert np.array_equal(second_least(v, vals, ok), least)


def test_opencv_morphology_is_ndimage_bit_for_bit(rng):
    """clpde.film._morph's dilation (with iterations and a mask), closing and 1-D extrema
    by OpenCV against scipy.ndimage's, at the frame's edges too."""
    from scipy import ndimage

    from clpde.film._morph import close, dilate, extreme1d

    lines = [np.ones((1, 3), bool), np.ones((1, 5), bool), np.ones((7, 1), bool)]
    for trial in range(40):
        m = rng.random((rng.integers(8, 40), rng.integers(8, 40))) < (0.02, 0.3)[trial % 2]
        m[0, : m.shape[1] // 2] = True  # on the edge
        allowed = rng.random(m.shape) < 0.6
        for it in (1, 2, 8):
            assert np.array_equal(dilate(m, it), ndimage.binary_dilation(m, iterations=it))
            assert np.array_equal(
                dilate(m, it, within=allowed),
                ndimage.binary_dilation(m, iterations=it, mask=allowed),
            )
        for st in lines:
            assert np.array_equal(dilate(m, structure=st), ndimage.binary_dilation(m, st))
            assert np.array_equal(close(m, st), ndimage.binary_closing(m, st))
        a = m.view(np.uint8) if trial % 2 else rng.standard_normal(m.shape).astype(np.float32)
        for size, axis, mode in ((3, 1, "nearest"), (5, 1, "reflect"), (31, 0, "constant")):
            for lowest, f in ((False, ndimage.maximum_filter1d), (True, ndimage.minimum_filter1d)):
                got = extreme1d(a, size, axis, mode, lowest)
                assert np.array_equal(got, f(a, size, axis=axis, mode=mode))


def test_median_of_is_numpy_median(rng):
    """The flicker fit's median (one partition) is np.median's value, odd and even counts,
    with ties."""
    from clpde.film._order import median_of

    for n in (1, 2, 3, 10, 11, 1000, 1001):
        for dtype in (np.float64, np.float32):
            x = rng.standard_normal(n).astype(dtype)
            x[: n // 3] = 0.25  # ties
            rng.shuffle(x)
            got, want = median_of(x), np.median(x)
            assert got == want and type(got) is type(want)


def test_restore_of_changed_pixels_is_the_whole_restore(rng):
    """The fill converts back only the pixels it changed: every value of 8- and 16-bit
    integer frames (grey and colour, channels on any axis) comes back as restore gives it,
    and float frames, whose round trip is not exact, take the whole restore."""
    from clpde.film._planes import film_planes

    cases = [
        (np.arange(256, dtype=np.uint8).reshape(4, 8, 8), None),
        (np.arange(65536, dtype=np.uint16).reshape(16, 64, 64), None),
        (np.arange(-32768, 32768, dtype=np.int16).reshape(16, 32, 32, 4), -1),
        (rng.integers(0, 256, (3, 3, 8, 9), dtype=np.uint8), 1),
        (rng.random((3, 8, 9, 3)).astype(np.float32), -1),
    ]
    for frames, axis in cases:
        planes, layout = film_planes(frames, axis)
        out = planes.copy()
        out[1, :, 2:5, 3] = rng.random((out.shape[1], 3), dtype=np.float32)
        assert np.array_equal(layout.restore_changed(out, planes), layout.restore(out))
        assert np.array_equal(layout.restore_changed(planes, planes), layout.restore(planes))


def test_threads_give_what_one_thread_gives(runtime, rng, monkeypatch):
    """The window's frames are detected and filled in threads (one per core): the same
    masks and frames, bit for bit, as one thread."""
    import os

    frames = _pan(_scene(rng), 6, grain=0.01, rng=rng)
    frames, _ = _blotches(frames, rng)
    runs = []
    for cores in (1, 4):
        monkeypatch.setattr(os, "cpu_count", lambda cores=cores: cores)
        mask = clpde.detect_defects(frames)
        runs.append((mask, clpde.inpaint_video(frames, mask, keep=3)))
    assert runs[0][0].any()
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])
