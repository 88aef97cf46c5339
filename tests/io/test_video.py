"""Video files through PyAV (clpde.io.video, clpde.io.video_probe): the one reader and the one
writer; films are restored by clpde.film (tests/film)."""

from fractions import Fraction

import numpy as np
import pytest

pytest.importorskip("av")

from clpde.io.video import read_video, write_video  # noqa: E402
from clpde.io.video_probe import video_info  # noqa: E402


def _film(height, width, count=30):
    """A smooth moving pattern (colour), and the same with a white vertical scratch."""
    yy, xx = np.mgrid[0:height, 0:width]
    frames = []
    for t in range(count):
        red = 120 + 70 * np.sin((xx + 2 * t) / 6.0)
        green = 110 + 60 * np.cos((yy - t) / 5.0)
        blue = 100 + 40 * np.sin((xx + yy + t) / 9.0)
        frames.append(np.stack([red, green, blue], axis=-1).astype(np.uint8))
    clean = np.stack(frames)
    mask = np.zeros((height, width), bool)
    mask[2:-2, width // 2 - 1 : width // 2 + 1] = True
    damaged = clean.copy()
    damaged[:, mask] = 255
    return clean, damaged, mask


@pytest.mark.parametrize("size", [(24, 32), (25, 33)])
def test_video_round_trip_keeps_count_rate_and_size(tmp_path, size):
    clean, _, _ = _film(*size)
    rate = Fraction(30000, 1001)
    path = write_video(tmp_path / "film.mp4", clean, rate)
    info = video_info(path)
    frames, read_rate = read_video(path)
    assert frames.shape == clean.shape  # odd sizes cropped back, never rescaled
    assert read_rate == rate and info.rate == rate and info.frames == 30
    assert (info.height, info.width) == size
    # H.264 4:2:0 (chroma at half resolution) at crf 17: close to the frames, in their order.
    error = np.abs(frames.astype(int) - clean).mean(axis=(1, 2, 3))
    assert error.max() < 6.0
    shifted = np.abs(frames[1:].astype(int) - clean[:-1]).mean(axis=(1, 2, 3))
    assert (shifted > error[1:]).all()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["film.mp4"]


WRITE_FILM = """
import sys
import numpy as np
from clpde.io.video import write_video
yy, xx = np.mgrid[0:144, 0:176]
frames = [np.stack([120 + 70 * np.sin((xx + 2 * t) / 6), 110 + 60 * np.cos((yy - t) / 5),
                    100 + 40 * np.sin((xx + yy + t) / 9)], axis=-1).astype(np.uint8)
          for t in range(30)]
write_video(sys.argv[1], frames, 25)
"""


def test_film_bytes_do_not_depend_on_the_heap(tmp_path):
    """The same frames give the same file whatever the heap held before: x264's mbtree read
    memory it never initialised, so glibc's MALLOC_PERTURB_ (which fills new allocations
    with a pattern) changed the bytes, and a film restored over workers differed from the
    serial loop's with the same frames."""
    import os
    import subprocess
    import sys

    files = []
    for name, perturb in (("plain.mp4", None), ("perturbed.mp4", "1")):
        env = {k: v for k, v in os.environ.items() if k != "MALLOC_PERTURB_"}
        if perturb:
            env["MALLOC_PERTURB_"] = perturb
        subprocess.run(
            [sys.executable, "-c", WRITE_FILM, str(tmp_path / name)],
            env=env,
            check=True,
            timeout=120,
        )
        files.append((tmp_path / name).read_bytes())
    assert files[0] == files[1]
