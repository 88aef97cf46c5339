"""scaled_frames' colour frames converted frame by frame (inputs.ColourFrames): the same
values as the whole clip converted at once, whatever the frames' dtype and the order of the
reads."""

import numpy as np
import pytest

from clpde.tracking.inputs import ColourFrames, scaled_frames


def _at_once(frames):
    """The clip's float64 (T, 3, H, W) copy scaled to [0, 1], as scaled_frames made it."""
    same = all(f.dtype == frames[0].dtype for f in frames)
    stack = np.stack(frames, dtype=None if same else np.float64)
    stack = np.moveaxis(stack[..., :3], -1, 1).astype(np.float64, order="C")
    lo, hi = float(stack.min()), float(stack.max())
    stack -= lo
    stack /= hi - lo
    return stack


def _clips():
    rng = np.random.default_rng(0)
    yield [rng.integers(0, 256, (12, 17, 3), dtype=np.uint8) for _ in range(6)]
    yield [rng.integers(0, 65536, (12, 17, 4), dtype=np.uint16) for _ in range(6)]  # alpha
    yield [(rng.random((12, 17, 3)) * 7 - 3).astype(np.float32) for _ in range(6)]
    yield [rng.random((12, 17, 3)) * 1e-3 + 5 for _ in range(6)]
    yield [  # mixed dtypes: stacked as float64
        rng.random((12, 17, 3)).astype(np.float32),
        rng.random((12, 17, 3)),
        rng.integers(0, 256, (12, 17, 3), dtype=np.uint8),
    ]


@pytest.mark.parametrize("clip", range(5))
def test_colour_frames_are_the_clip_converted_at_once(clip):
    frames = list(_clips())[clip]
    expected = _at_once(frames)
    lazy = scaled_frames(frames, True)
    assert isinstance(lazy, ColourFrames)
    assert lazy.shape == expected.shape and len(lazy) == len(expected)
    n = len(frames)
    for t in [0, 2, 1, n - 1, 0, -1, 1, 2, n - 2, 0]:  # kept and converted again
        assert lazy[t].dtype == np.float64 and lazy[t].flags.c_contiguous
        assert lazy[t].tobytes() == expected[t].tobytes()
    assert np.asarray(lazy).tobytes() == expected.tobytes()
    assert lazy[1:3].tobytes() == expected[1:3].tobytes()
    assert lazy.mean(axis=1).tobytes() == expected.mean(axis=1).tobytes()
    with pytest.raises(IndexError):
        lazy[n]


def test_a_flat_clip_is_zeros():
    frames = [np.full((5, 6, 3), 9, np.uint8)] * 3
    scaled = scaled_frames(frames, True)
    assert isinstance(scaled, np.ndarray) and scaled.shape == (3, 3, 5, 6) and not scaled.any()
