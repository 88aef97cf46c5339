"""progress= as a callable: it hears the run advance and can stop it by raising."""

import numpy as np
import pytest

import clpde
from clpde.data import damaged_astronaut


class Stop(Exception):
    pass


def stopper(calls: list, after: int = 1):
    def progress(done, total):
        calls.append((done, total))
        if len(calls) >= after:
            raise Stop

    return progress


def recorder(calls: list):
    return lambda done, total: calls.append((done, total))


@pytest.fixture(scope="module")
def photo():
    _, damaged, mask = damaged_astronaut()
    return damaged[:96, :96], mask[:96, :96]


def test_inpaint_reports_and_stops(photo):
    image, mask = photo
    calls = []
    out = clpde.inpaint(image, mask, channel_axis=-1, progress=recorder(calls))
    assert calls and out.shape == image.shape
    assert calls[-1][0] > 0
    with pytest.raises(Stop):
        clpde.inpaint(image, mask, channel_axis=-1, progress=stopper([]))


def test_denoise_tv_reports_and_stops():
    rng = np.random.default_rng(0)
    image = rng.random((64, 64)).astype(np.float32)
    calls = []
    clpde.denoise_tv(image, weight=0.1, progress=recorder(calls))
    assert calls and all(t is not None for _, t in calls)
    with pytest.raises(Stop):
        clpde.denoise_tv(image, weight=0.1, progress=stopper([]))


def test_diffuse_reports_and_stops():
    image = np.random.default_rng(1).random((48, 48)).astype(np.float32)
    calls = []
    clpde.diffuse(image, "heat", steps=120, progress=recorder(calls))
    assert calls[-1] == (120, 120)
    with pytest.raises(Stop):
        clpde.diffuse(image, "heat", steps=120, progress=stopper([]))


def test_track_reports_per_frame_and_stops():
    frames = np.zeros((4, 40, 40), np.float32)
    for t in range(4):
        frames[t, 10 + t : 25 + t, 10:25] = 1.0
    first = frames[0] > 0.5
    calls = []
    masks = clpde.track(frames, first, progress=recorder(calls))
    assert len(masks) == 4 and [d for d, _ in calls] == [1, 2, 3, 4]
    with pytest.raises(Stop):
        clpde.track(frames, first, progress=stopper([], after=2))


def test_bad_progress_is_one_clear_error():
    with pytest.raises(clpde.InputError, match="progress"):
        clpde.diffuse(np.zeros((8, 8), np.float32), "heat", steps=2, progress="yes")


def test_film_functions_report_and_stop():
    rng = np.random.default_rng(2)
    frames = np.stack([np.roll(rng.random((32, 40)), t, axis=1) for t in range(5)])
    frames = frames.astype(np.float32)
    frames[2, 10:14, 10:14] = 0.0
    calls = []
    mask = clpde.detect_defects(frames, progress=recorder(calls))
    assert calls[-1] == (2, 2)
    calls = []
    clpde.inpaint_video(frames, mask | (np.arange(5)[:, None, None] == 2), progress=recorder(calls))
    assert calls and calls[-1][0] == calls[-1][1]
    with pytest.raises(Stop):
        clpde.detect_defects(frames, progress=stopper([]))
