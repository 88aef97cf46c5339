"""Films through PyAV and `clpde inpaint VIDEO --mask MASK -o OUT.mp4` on a real 2-worker
LocalCluster (started once for the module)."""

from fractions import Fraction

import numpy as np
import pytest

pytest.importorskip("av")
pytest.importorskip("distributed")

import clpde  # noqa: E402
from clpde.cli import main  # noqa: E402
from clpde.film.restore import inpaint_sequence
from clpde.io.images import read_image, write_image  # noqa: E402
from clpde.io.video import VideoWriter, read_video, video_info, write_video


@pytest.fixture(scope="module")
def address():
    from clpde.scale.cluster import start_cluster

    cluster, _, _ = start_cluster(workers=2, threads=1)
    yield cluster.scheduler_address
    cluster.close()


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
    mask[2:-2, width // 2 - 1: width // 2 + 1] = True
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


def test_inpaint_video_command_restores_the_film(tmp_path, address, capsys):
    clean, damaged, mask = _film(25, 33)
    source = write_video(tmp_path / "damaged.mp4", damaged, 24)
    write_image(tmp_path / "mask.png", mask.astype(np.uint8) * 255)
    out = tmp_path / "restored.mp4"
    status = main(["inpaint", str(source), "--mask", str(tmp_path / "mask.png"), "-o", str(out),
                   "--scheduler", address, "--max-steps", "300", "--frames-per-task", "3"])
    assert status == 0, capsys.readouterr().err
    restored, rate = read_video(out)
    decoded, _ = read_video(source)
    assert restored.shape == clean.shape and rate == 24 and video_info(out).frames == 30
    before = np.abs(decoded[:, mask].astype(int) - clean[:, mask]).mean()
    after = np.abs(restored[:, mask].astype(int) - clean[:, mask]).mean()
    assert after < before / 5, (before, after)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["damaged.mp4", "mask.png", "restored.mp4"]


def test_film_restoration_gives_the_serial_loops_frames(tmp_path, address):
    """Over 2 workers, 3 frames a task: the frames handed to the encoder are bitwise those
    of a serial loop (decode, clpde.inpaint, write), in their order."""
    _, damaged, mask = _film(25, 33, count=12)
    source = write_video(tmp_path / "damaged.mp4", damaged, 24)
    write_image(tmp_path / "mask.png", mask.astype(np.uint8) * 255)
    result = inpaint_sequence(source, tmp_path / "mask.png", tmp_path / "restored.mp4",
                              scheduler=address, frames_per_task=3, max_steps=300)
    decoded, _ = read_video(source)
    with VideoWriter(tmp_path / "serial.mp4", 24) as serial:
        for frame in decoded:
            serial.write(clpde.inpaint(frame, mask, channel_axis=-1, max_steps=300))
    assert result.frames == 12 and result.frames_sha256 == serial.frames_sha256
    assert (tmp_path / "restored.mp4").read_bytes() == (tmp_path / "serial.mp4").read_bytes()


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
        subprocess.run([sys.executable, "-c", WRITE_FILM, str(tmp_path / name)], env=env,
                       check=True, timeout=120)
        files.append((tmp_path / name).read_bytes())
    assert files[0] == files[1]


def test_frame_folder_to_folder_equals_serial_inpainting(tmp_path, address):
    _, damaged, mask = _film(20, 26, count=6)
    frames, masks = tmp_path / "frames", tmp_path / "masks"
    frames.mkdir()
    masks.mkdir()
    for t, frame in enumerate(damaged):
        write_image(frames / f"scan{t + 1}.png", frame)  # natural order: scan2 before scan10
        write_image(masks / f"m{t + 1}.png", np.roll(mask, t, axis=1).astype(np.uint8) * 255)
    out = tmp_path / "out"
    result = inpaint_sequence(frames, masks, out, scheduler=address, frames_per_task=2,
                              max_steps=150)
    assert result.frames == 6
    for t in range(6):
        image = read_image(frames / f"scan{t + 1}.png")
        m = read_image(masks / f"m{t + 1}.png") > 0
        serial = clpde.inpaint(image, m, channel_axis=-1, max_steps=150)
        assert np.array_equal(read_image(out / f"scan{t + 1}.png"), serial)


def test_bad_mask_folder_fails_before_writing(tmp_path, address, capsys):
    _, damaged, mask = _film(16, 20, count=5)
    source = write_video(tmp_path / "film.mp4", damaged, 25)
    masks = tmp_path / "masks"
    masks.mkdir()
    for t in range(3):
        write_image(masks / f"m{t}.png", mask.astype(np.uint8) * 255)
    out = tmp_path / "out.mp4"
    assert main(["inpaint", str(source), "--mask", str(masks), "-o", str(out),
                 "--scheduler", address]) == 2
    assert "3 masks for 5 frames" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["film.mp4", "masks"]
    write_image(tmp_path / "small.png", np.zeros((8, 8), np.uint8))
    assert main(["inpaint", str(source), "--mask", str(tmp_path / "small.png"), "-o", str(out),
                 "--scheduler", address]) == 2
    assert "same size" in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.glob(".*.part"))
