"""Input validation and the round trip between user images and the kernels' layout.

Kernels see (channels, ny, nx) data scaled to [0, 1]; users get back an array of their own
shape, dtype and range. Inputs are never modified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from .errors import InputError


@dataclass
class ImageLayout:
    """How to turn kernel data back into an array like the user's."""

    shape: tuple
    dtype: np.dtype
    channel_axis: int | None
    offset: float
    scale: float

    def restore(self, data: np.ndarray) -> np.ndarray:
        """(nc, ny, nx) data in [0, 1] units back to the user's shape, dtype and range."""
        values = np.asarray(data, np.float64) * self.scale + self.offset
        if self.channel_axis is None:
            values = values[0]
        else:
            values = np.moveaxis(values, 0, self.channel_axis)
        if self.dtype == bool:  # a binary image stays binary: cut at one half
            return values > 0.5
        if np.issubdtype(self.dtype, np.integer):
            info = np.iinfo(self.dtype)
            values = np.clip(np.rint(values), info.min, info.max)
        elif abs(self.offset) + abs(self.scale) > 0.5 * float(np.finfo(self.dtype).max):
            big = float(np.finfo(self.dtype).max)  # rounding at the range's ends gives inf
            values = np.clip(values, -big, big)
        return values.astype(self.dtype)


def check_channel_axis(ndim: int, channel_axis: int | None) -> int | None:
    """The channel axis as a non-negative int (None for greyscale), checked against ndim."""
    if channel_axis is None:
        if ndim != 2:
            raise InputError(
                f"expected a 2-D greyscale image, got {ndim} dimensions; for a colour or "
                "multichannel image pass channel_axis (e.g. channel_axis=-1)"
            )
        return None
    if ndim != 3:
        raise InputError(
            f"channel_axis={channel_axis} needs a 3-D (rows, columns, channels) array, "
            f"got {ndim} dimensions; use channel_axis=None for a greyscale image"
        )
    if not isinstance(channel_axis, (int, np.integer)) or not -3 <= channel_axis < 3:
        raise InputError(f"channel_axis must be an integer in [-3, 2], not {channel_axis!r}")
    return int(channel_axis) % 3


def refuse_path(value, name: str = "image") -> None:
    """A file name where an array belongs gets the way to read the file, not a dtype."""
    import os

    if isinstance(value, (str, bytes, os.PathLike)):
        raise InputError(
            f"{name} is {os.fsdecode(value)!r}, a file name; pass an array (to read a file use "
            "clpde.io.read_image)"
        )


def mask_plane(mask: np.ndarray) -> np.ndarray:
    """The one plane of a mask, by one rule for arrays and files: a (rows, columns, channels)
    colour mask counts by its brightest colour channel, and an alpha channel (the last of
    two or four) is ignored; a (rows, columns) mask is returned as it is."""
    if mask.ndim != 3 or mask.shape[-1] > 4:
        return mask
    colours = mask.shape[-1] - 1 if mask.shape[-1] in (2, 4) else mask.shape[-1]
    return mask[..., :colours].max(axis=-1)


def as_image(image: ArrayLike, name: str = "image", allow_nan: bool = False) -> np.ndarray:
    """`image` as an array of bools, integers or floats, neither empty nor (unless allow_nan)
    holding NaN or infinite values; `name` names it in the error.

    A bool image is a binary one: the flows compute on it as 0/1 and return bool again,
    True where the result is above one half (ImageLayout.restore), as a thresholded
    level-set would."""
    refuse_path(image, name)
    array = np.asarray(image)
    if not (
        array.dtype == bool
        or np.issubdtype(array.dtype, np.integer)
        or np.issubdtype(array.dtype, np.floating)
    ):
        raise InputError(
            f"{name} has dtype {array.dtype}; expected bools, unsigned or signed integers or "
            "floats (convert with image.astype(np.float32))"
        )
    if array.size == 0:
        raise InputError(f"{name} is empty (shape {array.shape})")
    if np.issubdtype(array.dtype, np.floating) and not allow_nan:
        bad = ~np.isfinite(array)
        if bad.any():
            raise InputError(
                f"{name} contains {int(bad.sum())} NaN or infinite values; replace them "
                "(np.nan_to_num) or, to fill them in, use clpde.inpaint"
            )
    return array


def integer_range(dtype: DTypeLike) -> tuple[float, float]:
    """(offset, scale) mapping an integer dtype's whole range to [0, 1] (uint8: 0, 255;
    bool: 0, 1)."""
    if np.dtype(dtype) == bool:
        return 0.0, 1.0
    info = np.iinfo(dtype)
    return float(info.min), float(info.max) - float(info.min)


def value_range(lo: float, hi: float, name: str = "image") -> tuple[float, float]:
    """(offset, scale) mapping values in [lo, hi] to [0, 1]."""
    scale = hi - lo
    if not np.isfinite(scale):  # e.g. -1e308 .. 1e308: the span overflows float64
        raise InputError(
            f"{name} spans {lo:g} to {hi:g}, a range too wide for float64 arithmetic; "
            "scale it down first (e.g. image / 1e10)"
        )
    return lo, scale if hi > lo else 1.0


def to_kernel_layout(
    image: ArrayLike, channel_axis: int | None = None, name: str = "image", fits=None
) -> tuple[np.ndarray, ImageLayout]:
    """(data, layout): data as float64 (nc, ny, nx) scaled to [0, 1], plus how to undo it.

    Integer images are scaled by their dtype's range (uint8 0..255 -> 0..1; bool is 0/1);
    float images by their own minimum and maximum, so a flow's parameters mean the same for
    any input range.
    fits(shape), given, may refuse the (nc, ny, nx) shape before any conversion.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.imagedata import to_kernel_layout
    >>> rgb = np.zeros((4, 5, 3), np.uint8)
    >>> rgb[..., 1] = 255
    >>> data, layout = to_kernel_layout(rgb, channel_axis=-1)
    >>> data.shape, float(data[1].min()), layout.scale
    ((3, 4, 5), 1.0, 255.0)
    >>> bool((layout.restore(data) == rgb).all())
    True
    """
    array = as_image(image, name)
    axis = check_channel_axis(array.ndim, channel_axis)
    if fits is not None:
        rest = tuple(n for i, n in enumerate(array.shape) if i != axis)
        fits((1,) + array.shape if axis is None else (array.shape[axis],) + rest)
    if array.dtype == bool or np.issubdtype(array.dtype, np.integer):
        offset, scale = integer_range(array.dtype)
    else:
        offset, scale = value_range(float(array.min()), float(array.max()), name)
    data = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
    if min(data.shape[1:]) < 1:
        raise InputError(f"{name} has no pixels (shape {array.shape})")
    data = (data.astype(np.float64) - offset) / scale
    layout = ImageLayout(array.shape, array.dtype, axis, offset, scale)
    return np.ascontiguousarray(data), layout


def compute_dtype(image_dtype: DTypeLike, requested: DTypeLike | None = None) -> np.dtype:
    """float32 unless asked for float64."""
    if requested is None:
        return np.dtype(np.float32)
    requested = np.dtype(requested)
    if requested not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise InputError(f"precision must be float32 or float64, not {requested}")
    return requested


def positive(name: str, value) -> float:
    """A parameter that must be a finite positive number, as a float."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a positive number, not {value!r}") from None
    if not np.isfinite(number) or number <= 0:
        raise InputError(f"{name} must be a positive number, not {value!r}")
    return number


def check_steps(steps) -> int:
    """A number of steps: a non-negative integer (bools are refused)."""
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, not {steps!r}")
    return int(steps)


def check_time_step(dt, limit: float, what: str) -> float:
    """An explicit scheme's time step: 0.8 of the stability `limit` when None, else a
    positive number no larger than the limit. `what` names the scheme in the message."""
    if dt is None:
        return 0.8 * limit
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"dt must be a positive number, not {dt}")
    if dt > limit * (1 + 1e-9):
        raise InputError(
            f"dt={dt:g} is beyond the stability limit {limit:g} of the explicit {what} scheme; "
            f"use dt <= {limit:g}, or leave dt out for the default {0.8 * limit:g}"
        )
    return dt


@dataclass
class Channels:
    """An image split into the channels a flow works on and an untouched alpha channel."""

    colour: np.ndarray
    channel_axis: int | None
    alpha: np.ndarray | None
    squeezed: bool

    def join(self, result: np.ndarray) -> np.ndarray:
        """The flow's result on `colour` back in the input's layout, alpha restored."""
        result = np.asarray(result)
        if self.squeezed:
            result = result[..., np.newaxis]
        if self.alpha is not None:
            if result.ndim == 2:
                result = result[..., np.newaxis]
            result = np.concatenate([result, self.alpha[..., np.newaxis]], axis=-1)
        return result


def split_alpha(image: np.ndarray, name: str = "input") -> Channels:
    """Greyscale (rows, cols) or colour (rows, cols, 1..4); 2 and 4 channels end in alpha."""
    if image.ndim == 2:
        return Channels(image, None, None, False)
    if image.ndim != 3 or image.shape[-1] > 4:
        raise InputError(
            f"{name} has shape {image.shape}; expected a greyscale (rows, columns) or colour "
            "(rows, columns, channels<=4) image (multi-page TIFF stacks are not supported)"
        )
    alpha = None
    colour = image
    if image.shape[-1] in (2, 4):
        alpha, colour = image[..., -1], image[..., :-1]
    if colour.shape[-1] == 1:
        return Channels(colour[..., 0], None, alpha, alpha is None)
    return Channels(colour, -1, alpha, False)


def grow_mask(mask: ArrayLike, px: float) -> np.ndarray:
    """Grow a mask by a disc of radius `px` pixels: every pixel within `px` of the mask's
    support joins it.

    A scanned scratch or a thresholded mask often misses the damage's blurred rim, which
    the inpainting then copies inwards; growing the mask by a pixel or two takes the rim in.

    Parameters
    ----------
    mask : array_like, shape (rows, columns)
        bool (True = in the mask), integer (nonzero = in, e.g. a 0/255 mask) or float (a
        soft mask: the degree of damage in [0, 1], nonzero = in its support).
    px : float
        The disc's radius in pixels, >= 0: a pixel joins when its distance to the nearest
        pixel of the support is at most `px`. 0 returns a copy.

    Returns
    -------
    numpy.ndarray
        A new array of the mask's shape and dtype. The pixels already in the support keep
        their values; the grown ring gets True (bool), the support's largest value (integer:
        255 for a 0/255 mask) or 1.0 (float: fully damaged).

    Raises
    ------
    InputError
        If `px` is negative or not a finite number, or the mask is not a 2-D bool, integer
        or float array with finite values.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> dot = np.zeros((5, 5), bool)
    >>> dot[2, 2] = True
    >>> clpde.grow_mask(dot, 1).astype(int)
    array([[0, 0, 0, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 1, 1, 1, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 0, 0, 0]])
    >>> soft = np.array([[0.0, 0.0, 0.5, 0.0]])
    >>> clpde.grow_mask(soft, 1)
    array([[0. , 1. , 0.5, 1. ]])
    """
    px = growth(px)
    m = np.asarray(mask)
    if m.ndim != 2:
        raise InputError(f"a mask is a 2-D (rows, columns) array, not shape {m.shape}")
    if not (
        m.dtype == bool or np.issubdtype(m.dtype, np.integer) or np.issubdtype(m.dtype, np.floating)
    ):
        raise InputError(f"mask has dtype {m.dtype}; give a bool or numeric array")
    if np.issubdtype(m.dtype, np.floating) and not np.isfinite(m).all():
        raise InputError(
            "mask contains NaN or infinite values; a float mask is the degree of damage in [0, 1]"
        )
    out = m.copy()
    support = m != 0
    if px == 0 or not support.any():
        return out
    if m.dtype == bool:
        value = True
    elif np.issubdtype(m.dtype, np.integer):
        value = m[support].max()
    else:
        value = 1.0
    _grow_into(out, support, px, value)
    return out


def growth(px) -> float:
    """A mask's growth in pixels, checked: a finite number >= 0 (bools refused)."""
    if (
        isinstance(px, bool)
        or not isinstance(px, (int, float, np.integer, np.floating))
        or not np.isfinite(px)
        or px < 0
    ):
        raise InputError(f"the mask's growth must be a number of pixels >= 0, not {px!r}")
    return float(px)


_GROW_ROWS = 256  # rows per strip: the distance transform's memory follows the strip


def _grow_into(out: np.ndarray, support: np.ndarray, px: float, value) -> None:
    """Set `value` on the pixels within Euclidean distance `px` of `support`, not in it.

    Strip by strip, each taken with `px` rows above and below and cropped to the columns
    near the support: a pixel's nearest support pixel within `px` lies in those rows, so
    the distances are exact, while the transform's arrays (16 bytes a pixel) stay the
    size of a strip, not of the image, and strips far from the mask cost nothing."""
    from scipy import ndimage

    ny, nx = support.shape
    reach = int(np.floor(px))
    rows = np.flatnonzero(support.any(axis=1))
    for y0 in range(max(0, rows[0] - reach), min(ny, rows[-1] + reach + 1), _GROW_ROWS):
        y1 = min(y0 + _GROW_ROWS, ny)
        a, b = max(0, y0 - reach), min(ny, y1 + reach)
        cols = np.flatnonzero(support[a:b].any(axis=0))
        if cols.size == 0:
            continue
        c0, c1 = max(0, cols[0] - reach), min(nx, cols[-1] + reach + 1)
        block = support[a:b, c0:c1]
        near = ndimage.distance_transform_edt(~block)[y0 - a : y1 - a] <= px
        ring = near & ~block[y0 - a : y1 - a]
        out[y0:y1, c0:c1][ring] = value


# The difference of two discrete Laplacians (Immerkaer 1996): it annihilates constant, linear
# and most of the quadratic content of an image, and turns white noise of deviation sigma
# into values of deviation 6 sigma (the root of the sum of its squared weights, 36).
NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
MAD_TO_STD = 1.0 / 0.6744897501960817  # median |x| of a unit normal variable


def noise_std(u: np.ndarray) -> float:
    """Noise deviation of one 2-D channel: the median absolute value of its fine-scale
    residual, as for a normal variable. The median, not the mean, so that the edges and
    texture where the residual is large do not count as noise.

    Denoising (clpde.planar.rof.estimate_sigma) and film restoration use it.
    Tracking keeps its own estimator, clpde.tracking.adaptive.noise_variance (the MAD of a
    2x2 diagonal difference, centred on its median, over all channels of a frame) on
    purpose: the tracker's constants (CONTRAST_NOISE, QUIET_FACTOR, LIGHT_CHANGE) were chosen
    on its values, so swapping the estimator would change every tracking result. Its 1.4826
    and MAD_TO_STD are the same constant.

    Parameters
    ----------
    u : ndarray
        One channel, at least 3 x 3, as float64 for the exact result.

    Returns
    -------
    float
        The estimated standard deviation, in u's units.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> round(noise_std(rng.normal(0, 0.1, (256, 256))), 2)
    0.1
    """
    ny, nx = u.shape
    if ny < 3 or nx < 3:
        raise InputError(
            f"an image of {nx}x{ny} pixels is too small to estimate its noise "
            "from; give sigma or weight"
        )
    r = sum(
        NOISE_MASK[i, j] * u[i : ny - 2 + i, j : nx - 2 + j] for i in range(3) for j in range(3)
    )
    return float(np.median(np.abs(r))) * MAD_TO_STD / 6.0
