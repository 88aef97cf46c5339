"""clpde.io.frames.FrameSource: the one frame-sequence reader, of a video or a folder of
images, shared by a film restoration (one frame at a time) and the tracker (read_frames)."""

from fractions import Fraction

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.io.frames import FOLDER_RATE, FrameSource, read_frames
from clpde.io.images import write_image


def _folder(tmp_path, frames, names):
    folder = tmp_path / "frames"
    folder.mkdir()
    for name, frame in zip(names, frames, strict=True):
        write_image(folder / name, frame)
    return folder


def test_a_folder_streams_in_natural_name_order(tmp_path, rng):
    frames = (rng.random((11, 12, 10, 3)) * 255).astype(np.uint8)
    names = [f"scan{t + 1}.png" for t in range(11)]  # scan2 before scan10
    source = FrameSource(_folder(tmp_path, frames, names))
    assert (len(source), source.rate, source.shape, source.dtype) == (
        11,
        FOLDER_RATE,
        (12, 10, 3),
        np.uint8,
    )
    assert source.rate == Fraction(25) and source.reader is None
    assert np.array_equal(np.stack(list(source)), frames)
    assert np.array_equal(read_frames(source.path, grey=False), frames)


@pytest.mark.parametrize(
    ("second", "message"),
    [
        (np.zeros((12, 9), np.uint8), "all frames must have one size"),
        (np.zeros((12, 10, 3), np.uint8), "mixed grey and colour"),
        (np.zeros((12, 10), np.uint16), "all frames need one type"),
    ],
)
def test_a_frame_unlike_the_first_is_named(tmp_path, second, message):
    folder = _folder(tmp_path, [np.zeros((12, 10), np.uint8), second], ["a1.png", "a2.png"])
    with pytest.raises(InputError, match=message):
        list(FrameSource(folder))
    with pytest.raises(InputError, match=message):
        read_frames(folder)


def test_neither_a_video_nor_a_folder(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("no frames")
    with pytest.raises(InputError, match="neither a video"):
        FrameSource(text)
    with pytest.raises(InputError, match="does not exist"):
        FrameSource(tmp_path / "missing.mp4")


def test_a_video_streams_with_its_timestamps(tmp_path):
    pytest.importorskip("av")
    from clpde.io.video import write_video

    frames = np.stack([np.full((16, 18, 3), 40 * t, np.uint8) for t in range(5)])
    path = write_video(tmp_path / "clip.mkv", frames, 10, codec="ffv1")  # lossless
    source = FrameSource(path)
    assert (len(source), source.rate, source.shape, source.dtype) == (
        5,
        10,
        (16, 18, 3),
        np.uint8,
    )
    assert np.array_equal(np.stack(list(source)), frames)
    assert source.reader.timestamps == [0, 100, 200, 300, 400]  # Matroska counts in ms
