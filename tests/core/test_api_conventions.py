"""The API's shared shapes: one iteration verb yielding a State, one keyword for each choice
(dtype=, storage=, band_width=), and the old names gone: they are refused, not aliased."""

import warnings

import numpy as np
import pytest

import clpde
from clpde._progress import State


def _square():
    image = np.zeros((24, 24), np.uint8)
    image[6:18, 6:18] = 200
    return image


def test_planar_iterate_yields_states():
    states = list(clpde.PlanarFlow(_square(), "heat").iterate(steps=6, every=3))
    assert all(isinstance(s, State) for s in states)
    assert [s.step for s in states] == [3, 6] and states[-1].time > 0


def test_inpainting_iterates_and_has_no_other_verb():
    image = _square()
    mask = np.zeros(image.shape, bool)
    mask[10:14, 4:20] = True
    run = clpde.Inpainting(image, mask, max_steps=20)
    states = list(run.iterate(every=10))
    assert all(isinstance(s, State) and s.time is None for s in states)
    steps = [s.step for s in states]
    assert steps == sorted(steps) and steps[0] == 0 and steps[-1] > 0
    assert np.array_equal(states[-1].image, run.result) and not hasattr(run, "states")


def test_tracker_iterates_and_is_not_itself_iterable():
    yy, xx = np.mgrid[:32, :32]
    frames = np.stack(
        [((yy - 16) ** 2 + (xx - 12 - 2 * k) ** 2 < 36).astype(np.float32) for k in range(2)]
    )
    tracker = clpde.MorphingTracker(frames, frames[0] > 0, max_iterations=6)
    states = list(tracker.iterate())
    assert all(isinstance(s, State) for s in states)
    assert [s.step for s in states] == [s.index for s in states] == [0, 1]
    with pytest.raises(TypeError):
        iter(tracker)


def test_new_names_warn_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        list(clpde.PlanarFlow(_square(), "heat").iterate(steps=2, every=1))


def test_dtype_everywhere_and_precision_gone():
    image = np.random.default_rng(0).random((16, 16))
    new = clpde.diffuse(image, steps=3, dtype=np.float64)
    assert not np.array_equal(new, clpde.diffuse(image, steps=3))  # float32 differs
    assert clpde.denoise_tv(image, weight=0.2, max_steps=5, dtype=np.float64).dtype == np.float64
    mask = np.zeros(image.shape, bool)
    mask[6:10, 6:10] = True
    assert clpde.Inpainting(image, mask, dtype=np.float64).dtype == np.float64
    frames = np.stack([image, image])
    assert clpde.MorphingTracker(frames, mask, dtype=np.float64).dtype == np.float64
    with pytest.raises(clpde.InputError, match="precision"):
        clpde.diffuse(image, steps=3, precision=np.float64)
    with pytest.raises(TypeError, match="precision"):
        clpde.denoise_tv(image, weight=0.2, precision=np.float64)
    # the tracker's keywords are TrackOptions' fields: an unknown one is a clear InputError
    with pytest.raises(clpde.InputError, match="unknown tracking option.*precision"):
        clpde.MorphingTracker(frames, mask, precision=np.float64)


def test_reinitialize_is_the_one_spelling(runtime):
    from clpde.tracking.levelset import LevelSet

    y, x = np.mgrid[:32, :32]
    u0 = 2.0 * (np.hypot(x - 15.5, y - 16.2) - 8.0)
    level_set = LevelSet(runtime, u0, band_width=3.0)
    level_set.reinitialize(iterations=10)
    assert not hasattr(level_set, "reinitialise")


def test_band_width_is_the_one_spelling():
    from clpde.regions.tracker import RegionTracker
    from clpde.surface import ImplicitSurface

    assert ImplicitSurface.sphere(1.0, 0.1, band_width=6.0).outer == 6.0
    with pytest.raises(TypeError, match="band"):
        ImplicitSurface.sphere(1.0, 0.1, band=6.0)
    h = 1 / 32
    ax = (np.arange(32) - 15.5) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi, phihat = np.sqrt(x**2 + y**2 + z**2) - 0.2, (0.05 - z)[None]
    assert RegionTracker(phi, phihat, h, band_width=4.0).width == 4.0
    with pytest.raises(TypeError, match="band"):
        RegionTracker(phi, phihat, h, band=4.0)


def test_storage_is_the_one_keyword_for_band_storage():
    from clpde.tracking.storage import STORAGES

    assert set(STORAGES) == {"lists", "bricks8x8", "bricks16x4"}
    frames = np.zeros((2, 16, 16), np.float32)
    frames[:, 4:12, 4:12] = 1
    for old in ({"band_layout": "lists"}, {"layout": "lists"}):
        with pytest.raises(clpde.InputError, match="unknown tracking option"):
            clpde.MorphingTracker(frames, frames[0] > 0, **old)


def test_every_band_storage_is_chosen_from_one_kind_of_table():
    """Tracking, regions and surfaces take their storage's class from a StorageTable, whose
    choose is the one check of a storage name: the same message in all three."""
    from clpde.bricks import StorageTable
    from clpde.regions.api import STORAGE_CLASSES
    from clpde.surface.storage import FLOW_STATES
    from clpde.tracking.storage import STORAGES

    assert set(STORAGE_CLASSES) == set(FLOW_STATES) == {"lists", "bricks"}
    for table in (STORAGES, STORAGE_CLASSES, FLOW_STATES):
        assert isinstance(table, StorageTable)
        assert table.choose("lists") is table["lists"]
        for bad in ("octree", None):
            with pytest.raises(clpde.InputError, match=r"^storage must be one of 'lists', .*"):
                table.choose(bad)


def test_surface_denoise_info_is_a_dataclass():
    from clpde.surface import ImplicitSurface, SurfaceDenoiseInfo

    surf = ImplicitSurface.sphere(1.0, 0.1)
    noisy = surf.field(lambda x, y, z: (z > 0).astype(float)) + 0.05 * np.sin(
        40 * surf.field(lambda x, y, z: x)
    )
    _, info = surf.denoise_tv(noisy, sigma=0.05, t=0.02, return_info=True)
    assert isinstance(info, SurfaceDenoiseInfo) and info.steps > 0 and info.dt > 0
    assert len(info.lam_history) == -(-info.steps // 10) and info.lam == info.lam_history[-1]
    _, fixed = surf.denoise_tv(noisy, lam=1.0, t=0.02, return_info=True)
    assert fixed.lam_history is None and fixed.residual_variance is None
    with pytest.raises(TypeError):
        info["lambda"]


def test_method_options_live_in_their_options_classes_only():
    """inpaint's and track's signatures repeat no method option: the defaults are the
    options classes' alone (one place each), and the keywords reach them as overrides."""
    import dataclasses
    import inspect

    from clpde.inpainting import registry
    from clpde.inpainting.api import Inpainting, inpaint
    from clpde.tracking.options import TrackOptions
    from clpde.tracking.tracker import MorphingTracker, track

    for function in (inpaint, Inpainting.__init__):
        names = set(inspect.signature(function).parameters)
        for method in (*registry.available(), "auto"):
            own = {f.name for f in dataclasses.fields(registry.options(method))}
            # spectral's own colour and alpha share the image's keywords' names: they are
            # reached through SpectralOptions
            assert not own & names - {"colour", "alpha"}, (function, method, own & names)
    for function in (track, MorphingTracker.__init__):
        names = set(inspect.signature(function).parameters)
        assert not {f.name for f in dataclasses.fields(TrackOptions)} & names


def test_inpaint_return_shapes():
    from clpde.inpainting.api import InpaintInfo

    image = _square()
    mask = np.zeros(image.shape, bool)
    mask[10:14, 4:20] = True
    out = clpde.inpaint(image, mask, max_steps=12)
    out_info, info = clpde.inpaint(image, mask, max_steps=12, return_info=True)
    out_states, states = clpde.inpaint(image, mask, max_steps=12, snapshots=6)
    _, both = clpde.inpaint(image, mask, max_steps=12, snapshots=6, return_info=True)
    assert np.array_equal(out, out_info) and np.array_equal(out, out_states)
    assert isinstance(info, InpaintInfo) and info.snapshots == []
    assert [s.step for s in states] == [s.step for s in both.snapshots]


def test_tiled_forms_take_dtype():
    from clpde.planar import tiled

    image = np.random.default_rng(1).random((40, 40))
    new = tiled.diffuse(image, "tv", steps=4, chunks=16, dtype=np.float64)
    assert np.array_equal(new, clpde.diffuse(image, "tv", steps=4, dtype=np.float64))
