"""method="spectral": the device's frequency-selective fill against its numpy twin
(tests/reference/spectral.py), its maths (basis cosines, ramps), the dispatch's contract
(bit for bit outside the mask, dtypes) and its programs (no build per size or channels)."""

import numpy as np
import pytest

import clpde
from clpde.inpainting import spectral, spectral_plan
from tests.reference import spectral as ref

SMALL = dict(block=8, min_block=4, border=4, iterations=12)


def _photo_like(ny, nx, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:ny, 0:nx]
    image = 0.5 + 0.25 * np.sin(x / 5.0 + y / 9.0) + 0.15 * np.tanh((x - nx / 2) / 2.0)
    return image + 0.05 * rng.standard_normal((ny, nx))


def _scratches(ny, nx, seed=1):
    rng = np.random.default_rng(seed)
    mask = np.zeros((ny, nx), bool)
    for _ in range(3):
        r = int(rng.integers(2, ny - 4))
        mask[r : r + 2, int(rng.integers(0, nx // 2)) :] = True
    mask[int(ny * 0.3) : int(ny * 0.3) + 9, int(nx * 0.6) : int(nx * 0.6) + 11] = True  # a blob
    return mask


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize("nc", [1, 3])
def test_device_matches_numpy_reference(runtime, kind, nc):
    rng = np.random.default_rng(7)
    ny, nx = 40, 48
    if kind == "random":
        data = rng.random((nc, ny, nx))
    else:
        data = np.stack([_photo_like(ny, nx, seed=c) * (1 - 0.2 * c) for c in range(nc)])
    mask = _scratches(ny, nx)
    # one block size; blocks cut where little is known; two grids averaged
    for extra in (
        dict(split=0.0),
        dict(split=0.6),
        dict(split=0.3, shifts=2, cutoff=0.8),
        dict(per_pixel=0.5),
        dict(floor=0.05),  # high enough that most windows end early
        dict(stall=0.02),  # most windows end early, each by its own residual
        dict(minor=1.0),  # every channel takes every pick
    ):
        options = dict(SMALL, **extra)
        got = spectral.fill(data, mask, runtime, **options)
        want = ref.fill(data, mask, **options)
        diff = np.abs(got - want)[:, mask]
        # float32 against float64: a greedy pick may flip where two scores tie within
        # rounding, so most pixels agree to rounding and all closely
        assert np.quantile(diff, 0.95) < 1e-4, np.quantile(diff, 0.95)
        assert diff.mean() < 1e-3, diff.mean()
        assert np.array_equal(got[:, ~mask], data[:, ~mask])


@pytest.mark.parametrize("shape", [(64, 1), (16, 8), (1, 8)])
def test_every_work_group_shape_matches_numpy_reference(runtime, monkeypatch, shape):
    # the GPUs' shape (64 items, one candidate at a time) and vectors shared by several
    # items or walked by one, all on this device: the same fill
    monkeypatch.setattr(spectral, "work_shape", lambda rt: shape)
    data = np.stack([_photo_like(40, 48, seed=c) * (1 - 0.2 * c) for c in range(3)])
    mask = _scratches(40, 48)
    options = dict(SMALL, cutoff=0.8, minor=0.5)
    got = spectral.fill(data, mask, runtime, **options)
    want = ref.fill(data, mask, **options)
    diff = np.abs(got - want)[:, mask]
    assert np.quantile(diff, 0.95) < 1e-4, np.quantile(diff, 0.95)
    assert diff.mean() < 1e-3, diff.mean()


@pytest.mark.parametrize("items", [1, 16])
def test_vectors_give_the_scalar_fill_bit_for_bit(runtime, monkeypatch, items):
    # the same sums in the same order: only the number of items (the plane's partial sums)
    # may change the rounding
    data = np.stack([_photo_like(40, 48, seed=c) * (1 - 0.2 * c) for c in range(3)])
    mask = _scratches(40, 48)
    fills = []
    for vector in (1, 8):
        monkeypatch.setattr(spectral, "work_shape", lambda rt, v=vector: (items, v))
        fills.append(spectral.fill(data, mask, runtime, **dict(SMALL, cutoff=0.8)))
    assert np.array_equal(fills[0], fills[1])


def test_plan_matches_reference_plan():
    mask = _scratches(60, 70, seed=3)
    mask[0:3, 10:20] = True  # damage at the image's edge: shifted grids start before it
    for split, shift in ((0.0, (0, 0)), (0.5, (0, 0)), (0.8, (0, 0)), (0.5, (8, 8)), (0.5, (0, 8))):
        options = dict(block=16, min_block=4, border=8, split=split, delta=0.5, shift=shift)
        crop, blocks, waves, wave_of = spectral_plan.plan(mask, **options)
        crop_r, blocks_r, waves_r, wave_of_r = ref.plan(mask, **options)
        assert tuple(crop) == tuple(crop_r)
        assert np.array_equal(wave_of, wave_of_r)
        assert [n for _, n in waves] == [len(w) for w in waves_r]
        got = {tuple(b[:3]) for b in blocks.tolist()}
        assert got == set(blocks_r)
        assert all(b[3] == b[2] + 16 for b in blocks.tolist())


@pytest.mark.parametrize("freq", [(0, 3), (2, 1), (4, 4)])
def test_basis_cosine_is_restored_almost_exactly(runtime, freq):
    # block 16 + border 8 on each side: a 32-px window; a cosine of a basis frequency of
    # that window is one pair of the model (without the plane, which would take a slope out);
    # with a slow weight decay the pair is well told apart from its neighbours on the known
    # pixels (with rho = 0.6, tuned on photos, the far known pixels weigh too little for that)
    n = 96
    y, x = np.mgrid[0:n, 0:n]
    ky, kx = freq
    image = 0.5 + 0.35 * np.cos(2 * np.pi * (ky * y + kx * x) / 32 + 0.3)
    mask = np.zeros((n, n), bool)
    mask[40:52, 30:60] = True
    mask[70:73, 5:90] = True
    out = spectral.fill(
        image[None],
        mask,
        runtime,
        block=16,
        border=8,
        split=0.0,
        rho=0.8,
        gamma=0.5,
        shifts=1,
        iterations=60,
        detrend=False,
        floor=0.0,  # the maths alone: no stop once the residual is near the data's precision
    )[0]
    assert np.abs(out - image)[mask].max() < 1e-3


def test_linear_ramp_is_restored_well(runtime):
    n = 80
    y, x = np.mgrid[0:n, 0:n]
    image = 0.1 + 0.6 * x / n + 0.2 * y / n
    mask = np.zeros((n, n), bool)
    mask[30:40, 10:70] = True
    mask[60:62, :] = True
    out = spectral.fill(image[None], mask, runtime)[0]
    err = np.abs(out - image)[mask]
    # the biharmonic fill of the same hole is exact; a sum of periodic functions only
    # approximates a ramp over its window
    assert err.mean() < 0.01 and err.max() < 0.04, (err.mean(), err.max())


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_dtype_kept_and_outside_bit_for_bit(dtype):
    rng = np.random.default_rng(3)
    base = _photo_like(50, 60)
    if dtype == np.float32:
        image = (base * 40 - 7).astype(np.float32)
    else:
        top = np.iinfo(dtype).max
        image = np.clip(np.rint(base * top), 0, top).astype(dtype)
    colour = np.stack([image, image[::-1], image[:, ::-1]], -1)
    mask = _scratches(50, 60, seed=int(rng.integers(100)))
    for im, axis in ((image, None), (colour, -1)):
        out = clpde.inpaint(im, mask, channel_axis=axis, method="spectral", progress=False)
        assert out.dtype == im.dtype and out.shape == im.shape
        assert np.array_equal(out[~mask], im[~mask])
        assert np.isfinite(out.astype(np.float64)).all()


def test_sixteen_bits_keep_their_precision():
    # a smooth 16-bit ramp whose steps are far below 8 bits: the fill keeps them
    n = 64
    y, x = np.mgrid[0:n, 0:n]
    image = (20000 + 37 * x + 11 * y).astype(np.uint16)
    mask = np.zeros((n, n), bool)
    mask[20:26, 8:56] = True
    out = clpde.inpaint(image, mask, method="spectral", progress=False)
    err = np.abs(out.astype(float) - image)[mask]
    assert err.mean() < 20  # 257 would be one 8-bit step


def test_new_size_and_channel_count_build_no_program(runtime, monkeypatch):
    builds = []
    build = type(runtime)._build

    def counting(self, filename, dtype, defines):
        builds.append(filename)
        return build(self, filename, dtype, defines)

    monkeypatch.setattr(type(runtime), "_build", counting)
    rng = np.random.default_rng(0)
    data = rng.random((1, 30, 40))
    spectral.fill(data, _scratches(30, 40), runtime, **SMALL)  # may build (first use)
    builds.clear()
    spectral.fill(rng.random((1, 45, 37)), _scratches(45, 37), runtime, **SMALL)
    spectral.fill(rng.random((3, 45, 37)), _scratches(45, 37), runtime, **SMALL)
    spectral.fill(rng.random((2, 61, 29)), _scratches(61, 29), runtime, **SMALL)
    assert builds == []


def test_fills_in_two_threads_at_once_match_their_own_fills(runtime):
    # each thread launches its own kept instance of the kernel (spectral._bare_kernel): one
    # instance shared between threads would launch one fill's blocks on the other's buffers
    import threading

    rng = np.random.default_rng(4)
    jobs = [(rng.random((c, 40, 48)), _scratches(40, 48, seed=c)) for c in (1, 3)]
    alone = [spectral.fill(d, m, runtime, **SMALL) for d, m in jobs]
    got = [[], []]

    def run(k):
        for _ in range(4):
            got[k].append(spectral.fill(*jobs[k], runtime, **SMALL))

    threads = [threading.Thread(target=run, args=(k,)) for k in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in (0, 1):
        assert len(got[k]) == 4
        assert all(np.array_equal(g, alone[k]) for g in got[k])
    program = spectral.fitting_kernel(runtime, np.dtype(np.float32))[0].cl_kernel.program
    mine = spectral._bare_kernel(program)
    theirs = []
    other = threading.Thread(target=lambda: theirs.append(spectral._bare_kernel(program)))
    other.start()
    other.join()
    assert spectral._bare_kernel(program) is mine and theirs[0] is not mine


def test_bad_options_are_refused():
    image = np.zeros((20, 20), np.uint8)
    mask = np.zeros((20, 20), bool)
    mask[5:8, 5:8] = True
    with pytest.raises(clpde.InputError, match="window"):
        clpde.inpaint(image, mask, method="spectral", block=32, border=8)
    with pytest.raises(clpde.InputError, match="rho"):
        clpde.inpaint(image, mask, method="spectral", rho=1.5)
    with pytest.raises(clpde.InputError, match="stall"):
        clpde.inpaint(image, mask, method="spectral", stall=1.0)


def test_stall_ends_the_picks_on_noise_and_keeps_a_cosine():
    # stall: a window's picks end once the best pair would explain less than this share of
    # the weighted residual left. On white noise every pair explains little, so the picks
    # end early; a basis cosine is one pair that explains nearly all of it, so it is kept.
    L = 32
    weight = 0.6 ** np.hypot(*(np.mgrid[0:L, 0:L] - (L - 1) / 2))
    weight[12:20, 12:20] = 0  # the block's hole

    def model(values, stall, iterations=100):
        return ref.fit_block(
            values, weight, iterations=iterations, gamma=0.7, alpha=2.0, stop=0.0, stall=stall
        )

    noise = np.random.default_rng(3).standard_normal((L, L))
    stalled = model(noise, 0.005)
    # the picks it took: the fewest whose full fill (no stall) is the stalled one
    taken = next(n for n in range(101) if np.array_equal(model(noise, 0.0, n), stalled))
    assert 0 < taken < 100, taken
    y, x = np.mgrid[0:L, 0:L]
    cosine = np.cos(2 * np.pi * (2 * y + 3 * x) / L + 0.4)
    assert np.abs(model(cosine, 0.005) - cosine)[weight == 0].max() < 0.05


def test_small_holes_in_a_large_image_are_solved_in_small_boxes():
    # Each hole's box is its bounding box grown by MARGIN (a block plus the border, what the
    # fill reads), so only the boxes are converted and uploaded. A box that holds one hole
    # gives the whole-image call's fill bit for bit, and a far hole changes nothing in it.
    ny, nx = 240, 300
    image = np.stack([_photo_like(ny, nx, seed=c) for c in range(3)], -1).astype(np.float32)
    near, far = np.zeros((ny, nx), bool), np.zeros((ny, nx), bool)
    near[60:66, 80:94] = True
    far[190:197, 250:255] = True
    both = near | far
    margin = spectral.MARGIN(near)
    assert margin == 8 + 12
    out, info = clpde.inpaint(
        image, both, channel_axis=-1, method="spectral", return_info=True, progress=False
    )
    assert info.boxes == [
        (60 - margin, 66 + margin, 80 - margin, 94 + margin),
        (190 - margin, min(ny, 197 + margin), 250 - margin, min(nx, 255 + margin)),
    ]
    assert np.array_equal(out[~both], image[~both])
    for hole in (near, far):
        alone = clpde.inpaint(
            image, hole, channel_axis=-1, method="spectral", boxes=False, progress=False
        )
        assert np.array_equal(out[hole], alone[hole])
    grey = image[..., 0]
    boxed = clpde.inpaint(grey, near, method="spectral", progress=False)
    whole = clpde.inpaint(grey, near, method="spectral", boxes=False, progress=False)
    assert np.array_equal(boxed, whole)


def test_margin_refuses_bad_block_sizes():
    image = np.zeros((20, 20), np.uint8)
    mask = np.zeros((20, 20), bool)
    mask[5:8, 5:8] = True
    with pytest.raises(clpde.InputError, match="border"):
        clpde.inpaint(image, mask, method="spectral", border=None)


def test_thin_damage_takes_the_thin_border_and_thick_damage_the_border(runtime):
    rng = np.random.default_rng(5)
    data = rng.random((1, 48, 56))
    thin_mask = np.zeros((48, 56), bool)
    thin_mask[20:23, 4:50] = True  # a scratch 3 px wide: every pixel 2 px from known
    thick = thin_mask.copy()
    thick[14:28, 30:44] = True  # a 14 px square on it: its centre is 7 px from known
    assert spectral.thin(thin_mask) and not spectral.thin(thick)
    options = dict(SMALL, border=8)
    for mask, border in ((thin_mask, 3), (thick, 8)):
        got = spectral.fill(data, mask, runtime, thin_border=3, **options)
        want = spectral.fill(data, mask, runtime, **dict(options, border=border, thin_border=0))
        assert np.array_equal(got, want)
    # the other border's fill differs, so the comparison above can fail
    other = spectral.fill(data, thin_mask, runtime, **dict(options, thin_border=0))
    assert not np.array_equal(
        other, spectral.fill(data, thin_mask, runtime, thin_border=3, **options)
    )


def test_one_grid_in_double_precision_runs():
    # one grid's copy in float64 needs no conversion: the host's copy must still be its own
    # writable array (a broadcast view of the data was read-only, and the read-back failed)
    y, x = np.mgrid[0:24, 0:24]
    image = 0.5 + 0.3 * np.sin(x / 4.0) * np.cos(y / 5.0)
    mask = np.zeros((24, 24), bool)
    mask[10:12, 3:20] = True
    options = dict(method="spectral", shifts=1, iterations=5)
    double = clpde.inpaint(image, mask, dtype=np.float64, **options)
    single = clpde.inpaint(image, mask, **options)
    assert np.abs(double - single).max() < 1e-4
