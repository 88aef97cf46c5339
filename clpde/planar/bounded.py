"""Large images in bounded memory: the strips and tiles behind clpde.diffuse and
clpde.denoise_tv for images too large for a whole-image float64 copy.

flows.py and rof.py take these paths themselves (`is_large`); this module holds what they
share: the image converted and restored a strip at a time (`Scaled`), the tiles' spans,
and the channels' moments.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..imagedata import ImageLayout, as_image, check_channel_axis, integer_range, value_range

# clpde.diffuse and clpde.denoise_tv take these paths for images of more values than this
# (channels x rows x columns): below it the whole image in float64 and its device fields
# cost little; above it they cost tens of times the image (a 6000 x 4000 colour photo:
# several GB), and these paths keep to a fixed budget whatever the image's size.
LARGE_VALUES = 1 << 22
# Rows converted or restored at a time: float64 temporaries of a strip, not of the image.
STRIP_ROWS = 256
# denoise_tv's tiles: the kept core, and the margin on each side of it. A margin of 64
# keeps every kept pixel at least 64 px from a tile border that is not the image's own;
# the per-pixel stopping test makes a part of an image converge as it would on its own,
# so pixels that far in match the whole image's result (tests/planar/test_rof.py checks
# 60 px in).
TILE_CORE = 1024
TILE_MARGIN = 64
# With sigma, lambda is fitted on the image's central region of at most this many values.
LAMBDA_SAMPLE_VALUES = LARGE_VALUES


class Scaled:
    """An image's channels, converted to the kernels' [0, 1] float64 on demand, a block at
    a time, with the whole image's offset and scale (as to_kernel_layout converts it: the
    same arithmetic per value, so the same numbers), and restored into an output array of
    the input's shape and dtype."""

    def __init__(self, image, channel_axis):
        array = as_image(image)
        axis = check_channel_axis(array.ndim, channel_axis)
        if np.issubdtype(array.dtype, np.integer):
            offset, scale = integer_range(array.dtype)
        else:
            offset, scale = value_range(float(array.min()), float(array.max()))
        self.array = array
        self.channels = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
        self.nc, self.ny, self.nx = self.channels.shape
        if min(self.ny, self.nx) < 1:
            raise InputError(f"image has no pixels (shape {array.shape})")
        self.layout = ImageLayout(array.shape, array.dtype, axis, offset, scale)
        self._strip = ImageLayout((), array.dtype, None, offset, scale)
        self.out = np.empty_like(array)
        self.out_channels = self.out[np.newaxis] if axis is None else np.moveaxis(self.out, axis, 0)

    def block(self, rows: slice, cols: slice, channel=None) -> np.ndarray:
        """(nc, h, w) float64 of one block (all channels, or one)."""
        c = slice(None) if channel is None else slice(channel, channel + 1)
        data = self.channels[c, rows, cols]
        return (data.astype(np.float64) - self.layout.offset) / self.layout.scale

    def restore_value(self, value: float):
        """One kernel value restored as an output value."""
        return self._strip.restore(np.full((1, 1, 1), value))[0, 0]

    def restore(self, values: np.ndarray, rows: slice, cols: slice, channel=None) -> None:
        """Write (nc, h, w) kernel values (or (h, w) of one channel) into the output, strip
        by strip, with ImageLayout.restore's arithmetic."""
        values = values.reshape((-1,) + values.shape[-2:])
        channels = range(self.nc) if channel is None else [channel]
        for k, c in enumerate(channels):
            for r in range(0, values.shape[1], STRIP_ROWS):
                part = values[k, r : r + STRIP_ROWS]
                start = rows.start + r
                self.out_channels[c, start : start + part.shape[0], cols] = self._strip.restore(
                    part[np.newaxis]
                )


def is_large(image, channel_axis=None) -> bool:
    """Whether an image has more values than LARGE_VALUES (channels included)."""
    return int(np.prod(np.shape(image))) > LARGE_VALUES


def spans(n: int, core: int, margin: int):
    """(kept, read) slices along one axis: kept cores of `core` cells, each read with
    `margin` more on each side where the image has them."""
    for start in range(0, n, core):
        stop = min(start + core, n)
        yield slice(start, stop), slice(max(0, start - margin), min(n, stop + margin))


def channel_moments(scaled: Scaled) -> tuple[np.ndarray, np.ndarray]:
    """(mean, variance) of each channel in [0, 1] units, summed a strip at a time."""
    mean, var = np.empty(scaled.nc), np.empty(scaled.nc)
    n = scaled.ny * scaled.nx
    for c in range(scaled.nc):
        total = 0.0
        for r in range(0, scaled.ny, STRIP_ROWS):
            total += float(scaled.block(slice(r, r + STRIP_ROWS), slice(None), c).sum())
        mean[c] = total / n
        sq = 0.0
        for r in range(0, scaled.ny, STRIP_ROWS):
            block = scaled.block(slice(r, r + STRIP_ROWS), slice(None), c)
            sq += float(((block - mean[c]) ** 2).sum())
        var[c] = sq / n
    return mean, var
