"""Image files: round trips keep dtype and values, writes are atomic, inputs are protected."""

import os

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.io.images import (
    atomic_output,
    check_not_overwriting_input,
    read_image,
    write_gif,
    write_image,
)


def _image(rng, dtype, shape):
    if np.issubdtype(dtype, np.floating):
        return rng.random(shape).astype(dtype)
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, size=shape, endpoint=True).astype(dtype)


@pytest.mark.parametrize(
    "suffix, dtype, shape",
    [
        (".png", np.uint8, (7, 9)),
        (".png", np.uint8, (7, 9, 3)),
        (".png", np.uint8, (7, 9, 4)),
        (".png", np.uint16, (7, 9)),
        (".tif", np.uint16, (7, 9, 3)),
        (".tiff", np.float32, (7, 9)),
        (".tif", np.float64, (7, 9, 4)),
        (".tif", np.int16, (7, 9)),
    ],
)
def test_lossless_round_trip_keeps_dtype_and_values(tmp_path, rng, suffix, dtype, shape):
    image = _image(rng, dtype, shape)
    path = tmp_path / f"a{suffix}"
    write_image(path, image)
    back = read_image(path)
    assert back.dtype == image.dtype
    np.testing.assert_array_equal(back, image)


def test_jpeg_round_trip_is_close(tmp_path):
    yy, xx = np.mgrid[:32, :48]
    image = np.dstack([xx * 5, yy * 7, xx + yy]).astype(np.uint8)
    write_image(tmp_path / "a.jpg", image)
    back = read_image(tmp_path / "a.jpg")
    assert back.dtype == np.uint8 and back.shape == image.shape
    assert np.abs(back.astype(int) - image).mean() < 3


@pytest.mark.parametrize(
    "name, dtype, shape, words",
    [
        ("a.png", np.float32, (4, 4), "PNG stores"),
        ("a.png", bool, (4, 4, 3), "1-bit images as greyscale only"),
        ("a.jpg", np.uint8, (4, 4, 4), "JPEG"),
        ("a.bmp", np.uint8, (4, 4), "unsupported image format"),
        ("a.png", np.uint8, (4, 4, 5), "at most 4 channels"),
    ],
)
def test_unwritable_combinations_are_refused_and_write_nothing(tmp_path, name, dtype, shape, words):
    with pytest.raises(InputError, match=words):
        write_image(tmp_path / name, np.zeros(shape, dtype))
    assert os.listdir(tmp_path) == []


def test_missing_output_folder_is_a_clear_error(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        write_image(tmp_path / "no" / "a.png", np.zeros((4, 4), np.uint8))


def test_read_errors_name_the_path(tmp_path):
    with pytest.raises(InputError, match="missing.png.*does not exist"):
        read_image(tmp_path / "missing.png")
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png at all")
    with pytest.raises(InputError, match="bad.png") as info:
        read_image(bad)
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match="not a file"):
        read_image(tmp_path)
    (tmp_path / "a.bmp").write_bytes(b"BM")
    with pytest.raises(InputError, match="unsupported image format"):
        read_image(tmp_path / "a.bmp")


def test_write_replaces_existing_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "out.png"
    write_image(path, np.zeros((5, 5), np.uint8))
    write_image(path, np.full((5, 5), 9, np.uint8))
    assert os.listdir(tmp_path) == ["out.png"]
    assert (read_image(path) == 9).all()


def test_failed_write_keeps_old_file_and_removes_temporary(tmp_path):
    path = tmp_path / "out.png"
    write_image(path, np.full((5, 5), 3, np.uint8))
    with pytest.raises(RuntimeError), atomic_output(path) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("interrupted")
    assert os.listdir(tmp_path) == ["out.png"]
    assert (read_image(path) == 3).all()


def test_written_file_has_normal_permissions(tmp_path):
    path = tmp_path / "out.png"
    write_image(path, np.zeros((3, 3), np.uint8))
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_write_gif_frames_and_timing(tmp_path):
    import imageio.v3 as iio

    frames = [np.full((6, 8), v, np.float32) for v in (0.0, 0.5, 1.0)]
    path = write_gif(tmp_path / "a.gif", frames, duration=0.2)
    assert os.listdir(tmp_path) == ["a.gif"]
    back = iio.imread(path, index=None)
    assert back.shape[:3] == (3, 6, 8)
    assert [int(f.mean()) for f in back] == [0, 128, 255]
    meta = iio.immeta(path, index=0)
    assert meta["duration"] == 200 and meta["loop"] == 0


def test_write_gif_refuses_bad_frames(tmp_path):
    with pytest.raises(InputError, match="one shape"):
        write_gif(tmp_path / "a.gif", [np.zeros((4, 4)), np.zeros((5, 4))])
    with pytest.raises(InputError, match="at least one frame"):
        write_gif(tmp_path / "a.gif", [])
    with pytest.raises(InputError, match=".gif"):
        write_gif(tmp_path / "a.png", [np.zeros((4, 4))])
    assert os.listdir(tmp_path) == []


def test_overwrite_guard(tmp_path, monkeypatch):
    src = tmp_path / "in.png"
    write_image(src, np.zeros((3, 3), np.uint8))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="never overwrites"):
        check_not_overwriting_input([src], "in.png")  # relative and absolute spellings
    link = tmp_path / "link.png"
    os.link(src, link)
    with pytest.raises(InputError, match="never overwrites"):
        check_not_overwriting_input(str(src), link)  # a hard link is the same file
    (tmp_path / "sym.png").symlink_to(src)
    with pytest.raises(InputError, match="never overwrites"):
        check_not_overwriting_input([tmp_path / "sym.png"], src)
    check_not_overwriting_input([src], tmp_path / "other.png")


def test_unwritable_folder_error_names_the_output(tmp_path, monkeypatch):
    import tempfile

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(
        InputError, match=r"cannot write .*out.png: .* not writable \(Permission denied\)"
    ):
        write_image(tmp_path / "out.png", np.zeros((3, 3), np.uint8))


# ---- masks -------------------------------------------------------------
def _strokes(shape=(120, 160)):
    """Thin text-like strokes over about 2.5% of the pixels, as a damage mask."""
    mask = np.zeros(shape, bool)
    for k in range(6):
        mask[15 + 18 * k : 17 + 18 * k, 10:150] = True
    mask[:, 80:82] = True
    return mask


def test_a_jpeg_mask_is_binarised_at_half_its_range_with_a_warning(tmp_path):
    from PIL import Image

    from clpde.io.images import read_mask

    truth = _strokes()
    path = tmp_path / "mask.jpg"
    Image.fromarray(truth.astype(np.uint8) * 255).save(path, quality=75)  # Pillow's default
    grey = read_image(path)
    assert (grey > 0).sum() > 1.5 * truth.sum()  # ringing: "nonzero" would grow the mask
    with pytest.warns(UserWarning, match="lossy JPEG.*save masks as PNG"):
        mask = read_mask(path, truth.shape)
    assert mask.dtype == bool
    assert abs(int(mask.sum()) - int(truth.sum())) < 0.03 * truth.sum()
    assert (mask != truth).mean() < 0.002


@pytest.mark.parametrize(
    "levels, expected",
    [
        ((0, 255), None),  # drawn masks read as drawn, without a warning
        ((0, 1), None),  # a 0/1 label image too
        ((10, 200), None),
        ((0, 100, 255), "3 grey levels"),
    ],
)
def test_grey_masks_read_above_their_darkest_value(tmp_path, levels, expected):
    import warnings

    from clpde.io.images import read_mask

    values = np.array(levels, np.uint8)[np.arange(12) % len(levels)].reshape(3, 4)
    write_image(tmp_path / "m.png", values)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mask = read_mask(tmp_path / "m.png")
    np.testing.assert_array_equal(mask, values > levels[0])  # soft levels are inside
    assert [str(w.message) for w in caught if expected and expected in str(w.message)] or (
        expected is None and not caught
    )


def test_colour_and_uniform_masks(tmp_path):
    from clpde.io.images import read_mask

    rgba = np.zeros((4, 5, 4), np.uint8)
    rgba[..., 3] = 255  # alpha is ignored
    rgba[1, 2, 0] = 250  # a red pixel
    write_image(tmp_path / "c.png", rgba)
    expected = np.zeros((4, 5), bool)
    expected[1, 2] = True
    np.testing.assert_array_equal(read_mask(tmp_path / "c.png"), expected)
    write_image(tmp_path / "w.png", np.full((4, 5), 255, np.uint8))
    assert read_mask(tmp_path / "w.png").all()
    with pytest.raises(InputError, match="is 5x4 pixels but the image is 6x4; give a mask"):
        read_mask(tmp_path / "w.png", (4, 6))


# ---- large and empty files -------------------------------------------
def test_large_images_are_not_blocked_by_pillows_bomb_limit(tmp_path, monkeypatch):
    from PIL import Image

    image = np.arange(60 * 70, dtype=np.uint32).reshape(60, 70).astype(np.uint8)
    write_image(tmp_path / "big.png", image)
    # the limit scaled down: 4200 pixels are more than twice it, where Pillow refuses to open
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)
    np.testing.assert_array_equal(read_image(tmp_path / "big.png"), image)
    assert Image.MAX_IMAGE_PIXELS == 1000  # restored for the rest of the program


@pytest.mark.parametrize("suffix", [".png", ".tif", ".jpg"])
def test_an_empty_file_is_reported_as_empty(tmp_path, suffix):
    (tmp_path / f"e{suffix}").write_bytes(b"")
    with pytest.raises(InputError, match=r"is empty \(0 bytes\)"):
        read_image(tmp_path / f"e{suffix}")
