"""`clpde track INPUT --init MASK -o OUTDIR` and the sequence reading/writing behind it."""

import json

import imageio.v3 as iio
import numpy as np
import pytest
import tifffile
from test_track import iou, synthetic_sequence

from clpde.cli import main
from clpde.errors import InputError
from clpde.io.frames import contour_polygons, read_frames, to_grey
from clpde.io.video import read_video


@pytest.fixture
def sequence(tmp_path):
    frames, truth = synthetic_sequence("translate", frames=4)
    frames8 = (frames * 255).astype(np.uint8)
    stack = tmp_path / "stack.tif"
    tifffile.imwrite(stack, frames8, photometric="minisblack")  # one page per frame
    mask = tmp_path / "mask.png"
    iio.imwrite(mask, truth[0].astype(np.uint8) * 255)
    return stack, mask, frames8, truth


def test_tracks_a_tiff_stack_and_writes_masks_gif_and_polygons(tmp_path, sequence, capsys):
    stack, mask, frames8, truth = sequence
    out = tmp_path / "out"
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["contours.json", *[f"mask_{t:04d}.png" for t in range(4)], "overlay.gif"]
    for t in range(4):
        written = iio.imread(out / f"mask_{t:04d}.png") > 0
        assert iou(written, truth[t]) >= 0.9
    gif = iio.imread(out / "overlay.gif", index=None)
    assert gif.shape[:3] == frames8.shape
    data = json.loads((out / "contours.json").read_text())
    assert len(data["frames"]) == 4 and len(data["frames"][0]["polygons"]) == 1
    assert "wrote 6 files" in capsys.readouterr().err


def test_a_folder_of_colour_images_is_read_in_natural_order(tmp_path, sequence):
    _, mask, frames8, truth = sequence
    folder = tmp_path / "frames"
    folder.mkdir()
    for t, f in enumerate(frames8):  # frame_2 before frame_10: natural order
        iio.imwrite(folder / f"frame_{t * 8}.png", np.repeat(f[..., None], 3, axis=-1))
    np.testing.assert_array_equal(read_frames(folder), frames8)
    assert read_frames(folder, grey=False).shape == (*frames8.shape, 3)
    out = tmp_path / "out"
    assert main(["track", str(folder), "--init", str(mask), "-o", str(out), "--no-gif"]) == 0
    assert not (out / "overlay.gif").exists()
    assert iou(iio.imread(out / "mask_0003.png") > 0, truth[3]) >= 0.9


def test_overlays_of_colour_footage_are_in_colour(tmp_path, sequence):
    pytest.importorskip("av")
    _, mask, frames8, truth = sequence
    folder = tmp_path / "frames"
    folder.mkdir()
    for t, f in enumerate(frames8):  # a warm tint: red strongest, blue weakest
        tinted = np.stack([f, (0.6 * f).astype(np.uint8), (0.2 * f).astype(np.uint8)], -1)
        iio.imwrite(folder / f"frame_{t}.png", tinted)
    out = tmp_path / "out"
    assert main(["track", str(folder), "--init", str(mask), "-o", str(out), "--mp4"]) == 0
    assert iou(iio.imread(out / "mask_0003.png") > 0, truth[3]) >= 0.9
    gif = iio.imread(out / "overlay.gif", index=None)[..., :3].astype(float)
    pictures, _ = read_video(out / "overlay.mp4")
    for picture in (gif[0], pictures[0].astype(float)):
        bright = frames8[0] > 100  # where the tint shows: red well above blue
        assert (picture[..., 0] - picture[..., 2])[bright].mean() > 60


@pytest.mark.parametrize("problem", ["mask size", "empty mask", "frame sizes", "bad video"])
def test_bad_input_is_a_clear_error_and_writes_nothing(tmp_path, sequence, capsys, problem):
    stack, mask, frames8, truth = sequence
    if problem == "mask size":
        iio.imwrite(mask, truth[0][:50].astype(np.uint8) * 255)
        expected = "the frames are 64x64"
    elif problem == "empty mask":
        iio.imwrite(mask, np.zeros((64, 64), np.uint8))
        expected = "empty"
    elif problem == "frame sizes":
        stack = tmp_path / "frames"
        stack.mkdir()
        iio.imwrite(stack / "a1.png", frames8[0])
        iio.imwrite(stack / "a2.png", frames8[1][:60])
        expected = "one size"
    else:
        stack = tmp_path / "clip.mp4"
        stack.write_bytes(b"\x00\x01 this is not a video" * 40)
        expected = "cannot read"
    out = tmp_path / "out"
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clpde: error:") and expected in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing half-written


def test_grey_conversion_and_polygons():
    rgb = np.zeros((2, 3, 4, 3), np.uint8)
    rgb[..., 1] = 200
    grey = to_grey(rgb)
    assert grey.dtype == np.uint8 and grey.shape == (2, 3, 4) and (grey == 117).all()
    square = np.zeros((8, 8), bool)
    square[2:5, 3:7] = True
    (poly,) = contour_polygons(square)
    xs, ys = np.array(poly).T
    assert xs.min() == 2.5 and xs.max() == 6.5 and ys.min() == 1.5 and ys.max() == 4.5
    with pytest.raises(InputError, match="unsupported input"):
        read_frames(__file__)


def test_an_output_folder_holds_one_runs_files_only(tmp_path, sequence, capsys):
    """a short run after a long one into the same folder left the long run's files.
    Now a non-empty folder is refused, and --overwrite replaces it as a whole."""
    stack, mask, _frames8, truth = sequence
    out = tmp_path / "out"
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out)]) == 0
    long_run = sorted(p.name for p in out.iterdir())
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out), "--frames", "2"]) == 2
    assert "give --overwrite" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == long_run  # untouched
    assert (
        main(
            [
                "track",
                str(stack),
                "--init",
                str(mask),
                "-o",
                str(out),
                "--frames",
                "2",
                "--overwrite",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in out.iterdir()) == [
        "contours.json",
        "mask_0000.png",
        "mask_0001.png",
        "overlay.gif",
    ]
    assert (iio.imread(out / "mask_0000.png") > 0).sum() == truth[0].sum()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]  # no staging left
    # a folder with files clpde does not write is never replaced
    (out / "notes.txt").write_text("mine")
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out), "--overwrite"]) == 2
    assert "'notes.txt', which clpde does not write" in capsys.readouterr().err
    assert (out / "notes.txt").read_text() == "mine"
    # one rule for a missing parent in every command: create it first
    assert main(["track", str(stack), "--init", str(mask), "-o", str(tmp_path / "a" / "b")]) == 2
    assert "does not exist; create it first" in capsys.readouterr().err


def test_a_missing_video_backend_is_named(tmp_path, monkeypatch):
    import sys

    clip = tmp_path / "clip.mp4"
    clip.write_bytes(b"\x00" * 64)
    monkeypatch.setitem(sys.modules, "av", None)  # PyAV not installed
    with pytest.raises(InputError, match=r"clpde\[video\]"):
        read_frames(clip)


def test_mp4_overlay_is_written_by_the_video_writer_not_rescaled(tmp_path, sequence, capsys):
    av = pytest.importorskip("av")
    _, _, frames8, truth = sequence
    odd = frames8[:, :63, :61]  # odd height and width
    stack = tmp_path / "odd.tif"
    tifffile.imwrite(stack, odd, photometric="minisblack")
    mask = tmp_path / "odd_mask.png"
    iio.imwrite(mask, truth[0][:63, :61].astype(np.uint8) * 255)
    out = tmp_path / "out"
    assert (
        main(["track", str(stack), "--init", str(mask), "-o", str(out), "--mp4", "--no-gif"]) == 0
    )
    with av.open(str(out / "overlay.mp4")) as container:
        stored = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
    assert len(stored) == 4 and stored[0].shape == (64, 62, 3)  # padded for the encoder
    pictures, _ = read_video(out / "overlay.mp4")  # clpde's reader crops the padding off
    assert pictures.shape == (4, 63, 61, 3)
    grey = pictures[0].astype(float).mean(axis=-1)
    # The frame itself sits unscaled in the top-left corner (H.264 is lossy: a loose check).
    inside = ~truth[0][:63, :61]
    assert np.abs(grey - odd[0])[inside].mean() < 12
    assert not [p for p in out.iterdir() if p.name.endswith(".part")]
    # A second run replaces the folder, its MP4 included.
    assert (
        main(
            [
                "track",
                str(stack),
                "--init",
                str(mask),
                "-o",
                str(out),
                "--mp4",
                "--overwrite",
                "--frames",
                "2",
            ]
        )
        == 0
    )
    with av.open(str(out / "overlay.mp4")) as container:
        assert len(list(container.decode(video=0))) == 2


def test_options_reach_the_tracker_and_low_confidence_frames_are_reported(
    tmp_path, sequence, capsys
):
    stack, mask, frames8, truth = sequence
    bad = frames8.copy()
    bad[2] = np.random.default_rng(1).integers(0, 256, bad[2].shape)  # a broken frame
    broken = tmp_path / "broken.tif"
    tifffile.imwrite(broken, bad, photometric="minisblack")
    out = tmp_path / "out"
    assert (
        main(
            [
                "track",
                str(broken),
                "--init",
                str(mask),
                "-o",
                str(out),
                "--no-gif",
                "--discrepancy",
                "difference",
                "--motion",
                "velocity",
                "--features",
                "contrast",
                "--equalize",
                "match",
                "--shape-weight",
                "0.01",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "low confidence" in err and "frames 2" in err
    out = tmp_path / "out2"
    assert main(["track", str(stack), "--init", str(mask), "-o", str(out), "--no-gif"]) == 0
    assert "low confidence" not in capsys.readouterr().err
    assert iou(iio.imread(out / "mask_0003.png") > 0, truth[3]) >= 0.9
    assert (
        main(
            [
                "track",
                str(stack),
                "--init",
                str(mask),
                "-o",
                str(tmp_path / "out3"),
                "--shape-weight",
                "-1",
            ]
        )
        == 2
    )
    assert "--shape-weight" in capsys.readouterr().err
