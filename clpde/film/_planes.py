"""Frames in and out: validation, [0, 1] scaling, grey planes, masks, and the way back."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from ..imagedata import as_image


@dataclass
class FilmLayout:
    """How to turn (T, C, H, W) [0, 1] planes back into an array like the user's."""

    shape: tuple
    dtype: np.dtype
    channel_axis: int | None  # of the user's array
    photo: bool  # a single 2-D (or colour 3-D) image rather than a stack of frames
    offset: float
    scale: float
    # the user's frames, as given (not compared or printed: an array)
    source: np.ndarray | None = field(default=None, repr=False, compare=False)

    def _values(self, planes: np.ndarray) -> np.ndarray:
        """Planes' values on the user's scale, in the user's dtype (rounded and clipped for
        integers)."""
        values = np.asarray(planes, np.float64) * self.scale + self.offset
        if np.issubdtype(self.dtype, np.integer):
            info = np.iinfo(self.dtype)
            values = np.clip(np.rint(values), info.min, info.max)
        return values.astype(self.dtype)

    def restore_changed(self, planes: np.ndarray, before: np.ndarray) -> np.ndarray:
        """`restore(planes)`, converting only the pixels that differ from `before` (the
        planes film_planes made): the others are the source's own values. For integers of
        up to 16 bits that is exactly what restore gives (a value's round trip through the
        float32 planes moves it by at most 65535 * 2**-24 < 0.5 before rounding); a
        restored film whose damage covers a few percent of it skips most of the
        conversion. Other dtypes, and a single image, take restore."""
        exact = np.issubdtype(self.dtype, np.integer) and np.dtype(self.dtype).itemsize <= 2
        if self.photo or self.source is None or not exact:
            return self.restore(planes)
        out = np.array(self.source, self.dtype, copy=True)
        t, y, x = np.nonzero((planes != before).any(axis=1))
        view = (
            out[..., None] if self.channel_axis is None else np.moveaxis(out, self.channel_axis, -1)
        )
        view[t, y, x] = self._values(planes[t, :, y, x])  # (pixels, channels)
        return out

    def restore(self, planes: np.ndarray) -> np.ndarray:
        values = planes
        if self.photo:
            values = values[0]  # (C, H, W)
            values = (
                values[0]
                if self.channel_axis is None
                else np.moveaxis(values, 0, self.channel_axis)
            )
        elif self.channel_axis is None:
            values = values[:, 0]
        else:
            values = np.moveaxis(values, 1, self.channel_axis)
        return self._values(values)


def film_planes(
    frames: ArrayLike, channel_axis: int | None, name: str = "frames"
) -> tuple[np.ndarray, FilmLayout]:
    """(planes, layout): float32 (T, C, H, W) in [0, 1] and how to undo it.

    frames: (T, H, W), or (T, H, W, C) with channel_axis naming the channel axis (1, 2 or 3,
    or negative); a single image (H, W), or (H, W, C) with channel_axis, counts as T = 1.
    """
    array = as_image(frames, name)
    photo = False
    if channel_axis is None:
        if array.ndim == 2:
            photo, data = True, array[np.newaxis, np.newaxis]
        elif array.ndim == 3:
            data = array[:, np.newaxis]
        else:
            raise InputError(
                f"{name} has {array.ndim} dimensions; give (frames, rows, columns), or "
                "(frames, rows, columns, channels) with channel_axis=-1"
            )
        axis = None
    else:
        if array.ndim not in (3, 4) or not isinstance(channel_axis, (int, np.integer)):
            raise InputError(
                f"channel_axis={channel_axis!r} needs (frames, rows, columns, channels) frames "
                f"or one (rows, columns, channels) image, got {array.ndim} dimensions"
            )
        if not -array.ndim <= channel_axis < array.ndim:
            raise InputError(
                f"channel_axis={channel_axis} is outside {name}'s {array.ndim} dimensions"
            )
        axis = int(channel_axis) % array.ndim
        if array.ndim == 3:
            photo = True
            data = np.moveaxis(array, axis, 0)[np.newaxis]
        else:
            if axis == 0:
                raise InputError(
                    "channel_axis=0 is the frames' axis; the channels are "
                    "usually the last axis (channel_axis=-1)"
                )
            data = np.moveaxis(array, axis, 1)
    if min(data.shape[2:]) < 8:
        raise InputError(
            f"{name} of {data.shape[3]}x{data.shape[2]} pixels are too small; "
            "give frames of at least 8x8 pixels"
        )
    if np.issubdtype(array.dtype, np.integer):
        info = np.iinfo(array.dtype)
        offset, scale = float(info.min), float(info.max) - float(info.min)
    else:
        offset = float(array.min())
        scale = float(array.max()) - offset or 1.0
    if np.issubdtype(array.dtype, np.integer) and array.dtype.itemsize <= 2:
        # integers of up to 16 bits: each value's plane value once, in a table (the same
        # formula's numbers as below, without a float64 copy of the whole film)
        values = np.arange(info.min, info.max + 1, dtype=np.float64)
        table = ((values - offset) / scale).astype(np.float32)
        planes = table[data if info.min == 0 else data.astype(np.int32) - info.min]
    else:
        planes = ((data.astype(np.float64) - offset) / scale).astype(np.float32)
    layout = FilmLayout(array.shape, array.dtype, axis, photo, offset, scale, array)
    return np.ascontiguousarray(planes), layout


def grey(planes: np.ndarray) -> np.ndarray:
    """(T, H, W) float32: the channels' mean."""
    return np.ascontiguousarray(planes.mean(axis=1, dtype=np.float32))


def film_masks(masks: ArrayLike, shape_thw: tuple, photo: bool) -> np.ndarray:
    """(T, H, W) float32 degree of damage in [0, 1]: bool True and nonzero integers are 1."""
    m = np.asarray(masks)
    t, h, w = shape_thw
    want = (h, w) if photo else (t, h, w)
    if m.dtype != bool and not np.issubdtype(m.dtype, np.number):
        raise InputError(
            f"masks have dtype {m.dtype}; give bool or numeric masks (nonzero = damaged)"
        )
    if m.shape != want:
        if not photo and m.ndim == 3 and m.shape[0] != t and m.shape[1:] == (h, w):
            raise InputError(
                f"got {m.shape[0]} masks for {t} frames; give one (rows, columns) mask per frame"
            )
        raise InputError(
            f"masks have shape {m.shape} but the frames need {want}; give one "
            f"{h}x{w} (rows x columns) mask per frame"
        )
    if photo:
        m = m[np.newaxis]
    if m.dtype == bool or np.issubdtype(m.dtype, np.integer):
        return (m != 0).astype(np.float32)
    lo, hi = float(m.min()), float(m.max())
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or hi > 1:
        raise InputError(
            f"float masks must lie in [0, 1] (the degree of damage), found "
            f"[{lo:g}, {hi:g}]; rescale them or pass bool masks"
        )
    return m.astype(np.float32)
