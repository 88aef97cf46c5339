"""What the volume functions share: telling a volume from an image, the round trip between a
user's (Z, Y, X[, C]) array and the kernels' (channels, nz, ny, nx) data on [0, 1], the
voxel spacing, and the launch of kernels/volumes/volume.cl's kernels."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from ..imagedata import ImageLayout, as_image, integer_range, value_range
from ..runtime import Runtime


def is_volume(image, channel_axis, spacing) -> bool:
    """Whether the flows should take `image` as a volume: spacing given, four dimensions, or
    three without a channel axis (a colour image names its channel axis)."""
    ndim = np.ndim(image)
    return spacing is not None or ndim == 4 or (ndim == 3 and channel_axis is None)


def check_spacing(spacing) -> np.ndarray:
    """(hz, hy, hx) as three positive floats; 1 each when None."""
    if spacing is None:
        return np.ones(3)
    try:
        values = np.asarray(spacing, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        values = np.array([np.nan])
    if values.shape != (3,) or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise InputError(
            f"spacing must be three positive numbers (z, y, x), the voxel's size along each "
            f"axis, got {spacing!r}"
        )
    return values


def check_channel_axis(array: np.ndarray, channel_axis, spacing, name: str) -> int | None:
    """The channel axis of a volume (None for one channel), or one line saying what to pass."""
    if channel_axis is None:
        if array.ndim == 4:
            raise InputError(
                f"{name} has 4 dimensions: a volume with channels needs channel_axis "
                "(e.g. channel_axis=-1 for (Z, Y, X, C))"
            )
        if array.ndim == 3 and spacing is None and array.shape[-1] in (3, 4):
            raise InputError(
                f"{name} of shape {array.shape} may be a colour image or a volume: pass "
                "channel_axis=-1 for a colour image, or spacing=(1, 1, 1) for a (Z, Y, X) volume"
            )
        if array.ndim != 3:
            raise InputError(f"a volume has shape (Z, Y, X), got {array.ndim} dimensions")
        return None
    if array.ndim != 4:
        raise InputError(
            f"a volume with channel_axis={channel_axis} has 4 dimensions (Z, Y, X, C), got "
            f"{array.ndim}; leave channel_axis out for a (Z, Y, X) volume"
        )
    if not isinstance(channel_axis, (int, np.integer)) or not -4 <= channel_axis < 4:
        raise InputError(f"channel_axis must be an integer in [-4, 3], not {channel_axis!r}")
    return int(channel_axis) % 4


def to_volume_layout(
    volume: ArrayLike, channel_axis, spacing, name: str = "volume"
) -> tuple[np.ndarray, ImageLayout]:
    """(data, layout): float64 (nc, nz, ny, nx) on [0, 1] (integers by their dtype's range,
    floats by their own), and how to give back the user's shape, dtype and range."""
    array = as_image(volume, name)
    axis = check_channel_axis(array, channel_axis, spacing, name)
    if array.dtype == bool or np.issubdtype(array.dtype, np.integer):
        offset, scale = integer_range(array.dtype)
    else:
        offset, scale = value_range(float(array.min()), float(array.max()), name)
    data = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
    data = (data.astype(np.float64) - offset) / scale
    return np.ascontiguousarray(data), ImageLayout(array.shape, array.dtype, axis, offset, scale)


@dataclass
class VolumeGrid:
    """A (nc, nz, ny, nx) field's size, arithmetic and spacing on one device."""

    runtime: Runtime
    shape: tuple[int, int, int, int]
    dtype: np.dtype
    spacing: np.ndarray  # (hz, hy, hx)

    @property
    def inverse(self) -> tuple:
        """(1/hx, 1/hy, 1/hz) as the kernels' scalars (x first, as they take them)."""
        return tuple(self.dtype.type(1.0 / h) for h in self.spacing[::-1])

    @property
    def inverse2(self) -> tuple:
        """(1/hx^2, 1/hy^2, 1/hz^2) as the kernels' scalars."""
        return tuple(self.dtype.type(1.0 / h**2) for h in self.spacing[::-1])

    def scalar(self, value: float):
        return self.dtype.type(value)

    def launch(self, kernel, *args) -> None:
        """Run a volume kernel over every voxel, channels walked inside."""
        nc, nz, ny, nx = self.shape
        glob, local, xrun = self.runtime.grid_launch(nx, ny, nz)
        kernel(self.runtime.queue, glob, local, *args, *self.sizes(xrun))

    def sizes(self, xrun: int) -> tuple:
        """The kernels' trailing VOL_ARGS: nx, ny, nz, channels, voxels per work-item."""
        nc, nz, ny, nx = self.shape
        return tuple(np.int32(v) for v in (nx, ny, nz, nc, xrun))
