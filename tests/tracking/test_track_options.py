"""The tracker's options: one frozen TrackOptions, its defaults in one place, checked once,
the same object from Python and the command line."""

import dataclasses

import numpy as np
import pytest

import clpde
from clpde import InputError
from clpde.cli.batch import command_options
from clpde.scale.file_tasks import tracking_options
from clpde.tracking.options import (
    ADAPTIVE_ITERATIONS,
    APPEARANCE_WEIGHT,
    ITERATIONS,
    TrackOptions,
    track_options,
)


def test_track_options_are_frozen_and_resolve_their_defaults():
    options = TrackOptions(motion="checked")
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.tol = 0.1
    assert options.iterations == ITERATIONS and options.appearance_weight == 0.0
    # replace re-resolves what depends on other fields
    region = dataclasses.replace(options, region_weight=1.0)
    assert region.max_iterations is None and region.iterations == ADAPTIVE_ITERATIONS
    image = TrackOptions()  # the default: motion='image'
    assert image.motion == "image" and image.appearance_weight == APPEARANCE_WEIGHT
    assert image.iterations == ADAPTIVE_ITERATIONS
    assert TrackOptions(equalize=True).equalize == "match"
    assert TrackOptions(max_iterations=7).iterations == 7


@pytest.mark.parametrize(
    "bad,match",
    [
        ({"dt": 0.9}, "outside"),
        ({"discrepancy": "sad"}, "discrepancy must be"),
        ({"curvature": 0.3, "discrepancy": "ncc"}, "adaptive"),
        ({"storage": "tiles"}, "storage must be"),
        ({"equalize": "flat"}, "equalize must be"),
    ],
)
def test_bad_track_options_fail_in_one_line(bad, match):
    with pytest.raises(InputError, match=match) as error:
        TrackOptions(**bad)
    assert "\n" not in str(error.value)


def test_overrides_and_unknown_names():
    base = TrackOptions(features="edges")
    assert track_options(base, tol=0.01) == TrackOptions(features="edges", tol=0.01)
    assert track_options(base) is base
    with pytest.raises(InputError, match="unknown tracking option.*the options are features"):
        track_options(radius=3)


def test_track_with_options_equals_track_with_keywords():
    yy, xx = np.mgrid[:40, :40]
    frames = np.stack(
        [((yy - 20) ** 2 + (xx - 14 - 3 * t) ** 2 < 49).astype(np.float32) for t in range(3)]
    )
    first = frames[0] > 0.5
    options = TrackOptions(discrepancy="difference", max_iterations=12)
    by_object = clpde.track(frames, first, options=options, progress=False)
    by_keywords = clpde.track(
        frames, first, discrepancy="difference", max_iterations=12, progress=False
    )
    assert np.array_equal(by_object, by_keywords)
    tracker = clpde.MorphingTracker(frames, first, options=options, tol=0.05)
    assert tracker.options == dataclasses.replace(options, tol=0.05)


def _from_cli(argv):
    flags = command_options("track", argv)
    names = {f.name for f in dataclasses.fields(TrackOptions)}
    return tracking_options(**{k: v for k, v in flags.items() if k in names})


def test_the_command_line_builds_the_same_options_with_the_same_defaults():
    assert _from_cli([]) == TrackOptions()
    assert _from_cli(["--motion", "none", "--equalize", "global", "--features", "edges"]) == (
        TrackOptions(motion=None, equalize="global", features="edges")
    )
    assert _from_cli(["--no-smooth", "--min-size", "9"]) == TrackOptions(smooth=False, min_size=9)
    with pytest.raises(InputError, match="--shape-weight"):
        _from_cli(["--shape-weight", "-1"])
