"""Every dtype and channel count that clpde.io writes reads back as it was; 16-bit colour PNG
keeps its 16 bits, whoever wrote the file."""

import struct
import zlib

import numpy as np
import pytest

from clpde.imagedata import InputError
from clpde.io import read_image, write_image

DTYPES = [
    bool,
    np.uint8,
    np.uint16,
    np.int8,
    np.int16,
    np.uint32,
    np.int32,
    np.int64,
    np.uint64,
    np.float16,
    np.float32,
    np.float64,
]
SHAPES = [(5, 6), (5, 6, 1), (5, 6, 2), (5, 6, 3), (5, 6, 4)]


def _image(rng, dtype, shape):
    dtype = np.dtype(dtype)
    if dtype.kind == "b":
        return rng.random(shape) > 0.5
    if dtype.kind == "f":
        return (rng.random(shape) * 100 - 50).astype(dtype)
    info = np.iinfo(dtype)
    # the whole range, ends included (the largest value by hand: numpy's integers() cannot
    # draw up to 2**64 - 1)
    values = rng.integers(
        max(info.min, -(2**62)),
        min(info.max, 2**62),
        size=shape,
        dtype=np.int64 if info.min < 0 else np.uint64,
    ).astype(dtype)
    flat = values.reshape(-1)
    flat[0], flat[-1] = info.min, info.max
    return values


@pytest.mark.parametrize("suffix", [".png", ".tif"])
@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_every_accepted_dtype_and_channel_count_round_trips(tmp_path, rng, suffix, dtype):
    accepted = 0
    for shape in SHAPES:
        image = _image(rng, dtype, shape)
        path = tmp_path / f"{len(shape)}_{shape[-1]}{suffix}"
        try:
            write_image(path, image)
        except InputError as exc:  # refused before writing, with a one-line reason
            assert "\n" not in str(exc) and not path.exists()
            continue
        accepted += 1
        if image.ndim == 3:  # a channels-first array seen channels-last, as flows return
            write_image(path, np.moveaxis(np.ascontiguousarray(np.moveaxis(image, -1, 0)), 0, -1))
        back = read_image(path)
        assert back.dtype == image.dtype, (shape, back.dtype)
        # PNG has no one-channel colour type: (rows, columns, 1) comes back (rows, columns)
        expected = image[..., 0] if suffix == ".png" and shape[-1:] == (1,) else image
        assert back.shape == expected.shape
        np.testing.assert_array_equal(back, expected)
    if suffix == ".tif" or np.dtype(dtype) in (np.dtype(np.uint8), np.dtype(np.uint16)):
        assert accepted == len(SHAPES)  # TIFF takes everything, PNG every 8/16-bit layout
    elif dtype is bool:
        assert accepted == 2  # PNG: 1-bit greyscale only


def _png(array: np.ndarray) -> bytes:
    """A 16-bit PNG written by hand (no imaging library): what a scanner would write."""
    rows, cols = array.shape[:2]
    channels = 1 if array.ndim == 2 else array.shape[2]
    colour_type = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    raw = b"".join(b"\0" + array[y].astype(">u2").tobytes() for y in range(rows))

    def chunk(kind, data):
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    header = struct.pack(">IIBBBBB", cols, rows, 16, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_a_16_bit_png_from_elsewhere_reads_at_16_bits(tmp_path, rng, channels):
    shape = (7, 9) if channels == 1 else (7, 9, channels)
    image = rng.integers(0, 65535, size=shape, endpoint=True).astype(np.uint16)
    image.reshape(-1)[0] = 65535
    image.reshape(-1)[1] = 257  # equal bytes: 8-bit reading would keep it exactly
    path = tmp_path / "scan.png"
    path.write_bytes(_png(image))
    back = read_image(path)
    assert back.dtype == np.uint16
    np.testing.assert_array_equal(back, image)
