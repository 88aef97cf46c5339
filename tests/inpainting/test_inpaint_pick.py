"""method="pick" (clpde/inpainting/pick.py): the spectral fill, and the exemplar's on the
clusters of damage whose surround is periodic."""

import numpy as np
import pytest

import clpde
from clpde.errors import InputError
from clpde.inpainting import PickOptions, pick


def _tiles(ny=96, nx=96, seed=0):
    """Tiles of period 10 with sharp edges, a little noise: periodic surroundings."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:ny, 0:nx]
    image = 0.25 + 0.5 * (((x // 5) + (y // 5)) % 2) + 0.02 * rng.standard_normal((ny, nx))
    return np.clip(np.round(image * 255), 0, 255).astype(np.uint8)


def _smooth(ny=96, nx=96, seed=0):
    """A smooth random field (no period) as 8-bit data."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    field = ndimage.gaussian_filter(rng.standard_normal((ny, nx)), 6)
    field = (field - field.min()) / np.ptp(field)
    return np.round(40 + 170 * field).astype(np.uint8)


def _disc(shape, cy, cx, r):
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]]
    return np.hypot(y - cy, x - cx) <= r


def _run(image, mask, method):
    return clpde.inpaint(image, mask, method=method, progress=False, seed=0)


def test_a_hole_in_a_periodic_pattern_is_copied_by_the_exemplar():
    image = _tiles()
    mask = _disc(image.shape, 48, 50, 9)
    data = image[None] / 255.0
    assert pick.periodic_clusters(data, mask).sum() == mask.sum()
    picked, spectral = _run(image, mask, "pick"), _run(image, mask, "spectral")

    def rmse(out):
        return np.sqrt(np.mean((out[mask].astype(float) - image[mask]) ** 2))

    # the spectral fill cannot continue the tiles across 2 periods; the exemplar copies them
    # (from the spectral fill's box: method="exemplar" alone searches 128 px around), up to
    # the noise, whose copy errs by sqrt(2) x 0.02 x 255 = 7.2 levels RMS
    assert rmse(picked) < 8 < 0.7 * rmse(spectral), (rmse(picked), rmse(spectral))


def test_elsewhere_it_is_the_spectral_fill_bit_for_bit():
    image = _smooth()
    mask = _disc(image.shape, 40, 40, 8)
    mask[70:72, 10:90] = True  # and a scratch
    assert not pick.periodic_clusters(image[None] / 255.0, mask).any()
    # (the smooth route off: this field is smooth enough for it, below)
    picked = clpde.inpaint(image, mask, method="pick", progress=False, seed=0, route=False)
    assert np.array_equal(picked, _run(image, mask, "spectral"))


def test_a_mixed_box_takes_each_cluster_from_its_method():
    image = _tiles(96, 136)
    image[:, 56:] = _smooth(96, 136)[:, 56:]  # the right part smooth, without a period
    # each disc's measured window (its box grown by pick.WINDOW) on one side only
    mask = _disc(image.shape, 40, 24, 7) | _disc(image.shape, 40, 108, 7)
    periodic = pick.periodic_clusters(image[None] / 255.0, mask)
    assert periodic[40, 24] and not periodic[40, 108]
    out = _run(image, mask, "pick")
    assert out.dtype == image.dtype and np.array_equal(out[~mask], image[~mask])
    left = _disc(image.shape, 40, 24, 7)
    error = np.abs(out[left].astype(int) - image[left]).mean()
    spectral_error = np.abs(_run(image, mask, "spectral")[left].astype(int) - image[left]).mean()
    assert error < 0.7 * spectral_error, (error, spectral_error)


def test_a_thin_scratch_in_a_pattern_stays_spectral():
    image = _tiles()
    mask = np.zeros(image.shape, bool)
    mask[40:42, 10:80] = True  # 2 px: half-thickness 1, below MIN_RADIUS
    assert not pick.periodic_clusters(image[None] / 255.0, mask).any()


@pytest.mark.parametrize("angle", [0.0, 0.4, 1.1])
def test_a_blob_on_a_straight_edge_is_not_taken_for_a_period(angle):
    # a straight edge correlates with itself at every shift along it (periodicity ~1), but
    # repeats along that one line only; a lattice or stripes also repeat off it
    from clpde.inpainting import choose

    y, x = np.mgrid[0:96, 0:96].astype(float)
    t = (x - 48) * np.cos(angle) + (y - 48) * np.sin(angle)
    image = np.round(255 * (0.3 + 0.4 / (1 + np.exp(-t / 0.8)))).astype(np.uint8)
    mask = _disc(image.shape, 48, 48, 6)
    data = image[None] / 255.0
    detail, ok = choose._detail(data, ~mask)
    assert choose._periodicity(detail, ok) > 0.95  # the old measure's false period
    assert choose.repeat(detail, ok) < 0.5
    assert not pick.periodic_clusters(data, mask).any()
    stripes = np.round(255 * (0.5 + 0.4 * np.sin(2 * np.pi * t / 10))).astype(np.uint8)
    assert pick.periodic_clusters(stripes[None] / 255.0, mask).sum() == mask.sum()


def _two_colours(angle=0.5, ny=96, nx=96):
    """Two flat colours meeting on a straight edge through the centre, a little noise."""
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    t = (x - nx / 2) * np.cos(angle) + (y - ny / 2) * np.sin(angle)
    image = np.where((t < 0)[..., None], [60.0, 140.0, 60.0], [220.0, 170.0, 140.0])
    image = image + rng.normal(0, 3, image.shape)
    return np.clip(np.round(image), 0, 255).astype(np.uint8)


def test_a_border_of_two_colours_reads_as_an_edge():
    image = _two_colours()
    mask = _disc(image.shape[:2], 48, 48, 7) | _disc(image.shape[:2], 15, 15, 7)
    gap, separation = pick.edge_contrast(np.moveaxis(image, -1, 0) / 255.0, mask)
    # cluster 1 (top left) sits in one flat colour: noise only; cluster 2 on the edge
    assert separation[1] > 2 * max(separation[0], 1.8) and gap[1] > 0.3 > gap[0]
    smooth = _smooth()
    gap, separation = pick.edge_contrast(smooth[None] / 255.0, _disc(smooth.shape, 48, 48, 7))
    assert separation[0] < pick.EDGE_SEPARATION


def test_the_smooth_vote_gives_a_smooth_field_to_the_biharmonic_fill():
    from scipy import ndimage

    rng = np.random.default_rng(3)
    field = ndimage.gaussian_filter(rng.standard_normal((96, 96)), 12)
    image = ((field - field.min()) / np.ptp(field)).astype(np.float32)
    mask = _disc(image.shape, 48, 48, 11)
    out = {
        name: clpde.inpaint(image, mask, method=m, progress=False, seed=0, **extra)
        for name, m, extra in (
            ("spectral", "spectral", {}),
            ("pick", "pick", {"route": False}),
            ("smooth", "pick", {"smooth": True, "route": False}),
        )
    }
    error = {k: np.sqrt(np.mean((v[mask] - image[mask]) ** 2)) for k, v in out.items()}
    assert np.array_equal(out["pick"], out["spectral"])  # the vote is off by default
    assert error["smooth"] < 0.7 * error["spectral"], error


def _voids(seed=5):
    """A smooth field (no period, no edge) with three thick voids: the smooth vote's case."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    field = ndimage.gaussian_filter(rng.standard_normal((112, 112)), 10)
    image = ((field - field.min()) / np.ptp(field)).astype(np.float32)
    mask = _disc(image.shape, 30, 30, 8) | _disc(image.shape, 75, 40, 6)
    return image, mask | _disc(image.shape, 60, 85, 10)


def test_the_quick_ring_test_chooses_as_the_full_one_with_fewer_picks(monkeypatch):
    from clpde.inpainting import registry
    from clpde.runtime import get_runtime

    image, mask = _voids()
    clusters, count, _ = pick.clusters_of(mask)
    filled = clpde.inpaint(image, mask, method="spectral", progress=False, seed=0)[None]
    common = {"dtype": np.float32, "progress": None, "seed": 0}
    args = (filled.astype(np.float64), mask, clusters, np.arange(1, count + 1), get_runtime())
    spectral = registry.load("spectral")
    picks = []
    solve = spectral.solve

    def counted(*a, **kw):
        picks.append(kw["iterations"])
        return solve(*a, **kw)

    monkeypatch.setattr(spectral, "solve", counted)
    quick = pick._ring_test(*args, common, pick.SpectralOptions())
    # the vote as it was: the spectral prediction with every pick of the fill
    monkeypatch.setattr(pick, "RING_SPECTRAL", {})
    full = pick._ring_test(*args, common, pick.SpectralOptions())
    assert len(full) >= 2  # the smooth field's voids go to the biharmonic fill
    assert quick == full and picks == [40, pick.SpectralOptions().iterations], (quick, full)


def test_the_smooth_vote_leaves_a_hole_on_an_edge_to_the_spectral_fill():
    image = _two_colours()
    mask = _disc(image.shape[:2], 48, 48, 7)
    runs = [
        clpde.inpaint(image, mask, channel_axis=-1, method="pick", progress=False, seed=0, **e)
        for e in ({}, {"smooth": True})
    ]
    assert np.array_equal(*runs)
    # and no side's colour is carried into the other: each hole pixel is near one of them
    sides = np.array([[60, 140, 60], [220, 170, 140]], float)
    near = np.abs(runs[0][mask].astype(float)[:, None] - sides[None]).max(axis=-1).min(axis=-1)
    assert np.mean(near > 40) < 0.1


def test_a_smooth_field_s_voids_take_the_smooth_route():
    image, mask = _voids()
    parts = pick.clusters_of(mask)
    labels = pick.smooth_clusters(image[None].astype(float), mask, parts, np.zeros_like(mask))
    assert list(labels) == [1, 2, 3]
    out = {m: _run(image, mask, m) for m in ("pick", "spectral")}
    routed_off = clpde.inpaint(image, mask, method="pick", progress=False, seed=0, route=False)
    assert np.array_equal(routed_off, out["spectral"])
    error = {k: np.sqrt(np.mean((v[mask] - image[mask]) ** 2)) for k, v in out.items()}
    # (0.67 with the spectral fill's every pick, 0.73 since its picks stall at 0.005: the
    # smooth field's windows end early, and better; unrouted, the ratio would be 1)
    assert error["pick"] < 0.8 * error["spectral"], error


def test_a_large_routed_cluster_is_solved_on_the_device_alike(monkeypatch):
    image, mask = _voids()
    host = _run(image, mask, "pick")
    monkeypatch.setattr(pick, "HOST_MAX", 100)  # every void over it: the device's solve
    device = _run(image, mask, "pick")
    assert not np.array_equal(host, device)
    assert np.abs(host[mask] - device[mask]).max() < 0.01 * np.ptp(image)


def _texture(ny=96, nx=96, seed=2):
    """Fine-grained texture: noise blurred by 1 px over a gentle shading, as 8-bit data."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:ny, 0:nx]
    fine = ndimage.gaussian_filter(rng.standard_normal((ny, nx)), 1.0)
    image = 120 + 0.3 * x + 40 * fine / fine.std()
    return np.clip(np.round(image), 0, 255).astype(np.uint8)


def test_texture_keeps_the_spectral_fill():
    image = _texture()
    thick = _disc(image.shape, 48, 48, 9)
    thin = np.zeros(image.shape, bool)
    thin[20:22, 10:86] = True  # 2 px: no cluster thick enough to be routed
    data = image[None] / 255.0
    for mask in (thin, thin | thick):
        parts = pick.clusters_of(mask)
        assert not pick.smooth_clusters(data, mask, parts, np.zeros_like(mask)).size
        assert np.array_equal(
            _run(image, mask, "pick"),
            clpde.inpaint(image, mask, method="pick", progress=False, seed=0, route=False),
        )


def test_the_host_biharmonic_fill_keeps_a_quadratic():
    from clpde.inpainting import smooth

    y, x = np.mgrid[0:64, 0:72] / 64.0
    image = (0.3 + 0.2 * x + 0.1 * y**2 - 0.2 * x * y)[None]
    mask = _disc((64, 72), 30, 30, 9)
    mask[0:5, 50:60] = True  # on the image's edge: filled from inside only, near the plane
    clusters, count, _ = pick.clusters_of(mask)
    out = smooth.fill(np.where(mask, 0.0, image), mask, clusters, [1, 2])
    inner = _disc((64, 72), 30, 30, 9)
    assert np.abs(out - image)[0][inner].max() < 1e-9
    assert np.abs(out - image)[0][mask].max() < 0.01
    errors, spread = smooth.ring_errors(np.where(mask, 0.0, image), mask, clusters, [2], 4)
    assert errors[0] < 1e-18 < spread[0]


def test_options_are_checked():
    with pytest.raises(InputError, match="periodicity must be in"):
        PickOptions(periodicity=1.5)
    with pytest.raises(InputError, match="smooth must be True or False"):
        PickOptions(smooth=1)
    with pytest.raises(InputError, match="route must be True or False"):
        PickOptions(route=1)
    with pytest.raises(InputError, match="spectral must be SpectralOptions"):
        PickOptions(spectral=3)


def test_a_gaussian_field_is_told_from_texture_and_edges():
    from scipy import ndimage

    from clpde.inpainting import fields
    from tests.cases.inpaint_corpus import fractal

    ok = np.ones((96, 96), bool)
    rough = fractal(0, 96).astype(float)
    assert fields.gaussian(rough, ok)
    assert fields.power_law(rough, ok) < fields.SMOOTH_ALPHA  # 0.68
    smooth = ndimage.gaussian_filter(np.random.default_rng(0).standard_normal((96, 96)), 6)
    assert fields.gaussian(smooth, ok)
    assert fields.power_law(smooth, ok) >= fields.SMOOTH_ALPHA  # 1.94
    # fine texture: Gaussian, but its variogram stops growing within a few pixels
    assert fields.gaussian(_texture().astype(float), ok)
    assert np.isnan(fields.power_law(_texture().astype(float), ok))
    # an edge under noise: Gaussian differences between pixels (kurtosis 2.96), but not
    # between 2 x 2 bins (3.68), where the noise is halved and the edge stays
    y, x = np.mgrid[0:96, 0:96]
    step = 50.0 * (x > 0.6 * y + 20) + np.random.default_rng(0).normal(0, 20, (96, 96))
    assert abs(fields._kurtosis(fields._differences(step, ok)) - 3) < fields.KURTOSIS_BAND
    assert not fields.gaussian(step, ok)
    assert not fields.gaussian(_tiles().astype(float), ok)


def test_voids_in_a_rough_gaussian_field_take_the_harmonic_fill():
    from clpde.inpainting import smooth
    from tests.cases.inpaint_corpus import fractal

    image = fractal(1, 96)
    mask = _disc(image.shape, 40, 44, 9) | _disc(image.shape, 75, 20, 6)
    clusters, count, _ = pick.clusters_of(mask)
    host = smooth.fill(np.where(mask, 0.0, image)[None], mask, clusters, [1, 2], order=1)[0]
    out = _run(np.where(mask, np.nan, image), mask, "pick")
    assert np.allclose(out[mask], host[mask], rtol=0, atol=1e-3)
    spectral = clpde.inpaint(image, mask, method="pick", progress=False, seed=0, route=False)
    error = {
        k: np.sqrt(np.mean((v[mask] - image[mask]) ** 2))
        for k, v in (("pick", out), ("spectral", spectral))
    }
    assert error["pick"] < error["spectral"], error


def test_the_host_harmonic_fill_keeps_a_plane_not_a_quadratic():
    from clpde.inpainting import smooth

    y, x = np.mgrid[0:64, 0:72] / 64.0
    mask = _disc((64, 72), 30, 30, 9)
    clusters, _, _ = pick.clusters_of(mask)
    plane = (0.3 + 0.2 * x - 0.1 * y)[None]
    out = smooth.fill(np.where(mask, 0.0, plane), mask, clusters, [1], order=1)
    assert np.abs(out - plane).max() < 1e-9
    bowl = (0.3 + 0.2 * x**2 + 0.2 * y**2)[None]
    out = smooth.fill(np.where(mask, 0.0, bowl), mask, clusters, [1], order=1)
    assert np.abs(out - bowl)[0][mask].max() > 1e-3  # (the biharmonic fill keeps it)
    out = smooth.fill(np.where(mask, 0.0, bowl), mask, clusters, [1])
    assert np.abs(out - bowl)[0][mask].max() < 1e-9


def test_a_large_harmonic_cluster_is_solved_on_the_device_alike(monkeypatch):
    from tests.cases.inpaint_corpus import fractal

    image = fractal(1, 96)
    mask = _disc(image.shape, 40, 44, 9)
    host = _run(image, mask, "pick")
    monkeypatch.setattr(pick, "HOST_MAX", 100)  # the void over it: the device's solve
    device = _run(image, mask, "pick")
    assert not np.array_equal(host, device)
    assert np.abs(host[mask] - device[mask]).max() < 0.01 * np.ptp(image)
