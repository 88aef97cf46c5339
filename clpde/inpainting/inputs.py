"""The image and mask of an inpainting call, checked and scaled for every method alike:
the mask read as omega (where to fill) and an optional softness (a float mask's degree of
damage), NaN pixels checked against it, the alpha channel and the colour model checked, and
the [0, 1] scaling of the data found, without a float copy of the image (api.py converts
one box at a time)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..imagedata import (
    ImageLayout,
    as_image,
    check_channel_axis,
    integer_range,
    mask_plane,
    refuse_path,
    value_range,
)

COLOUR_MODELS = ("channels", "rho-phi-psi")


def as_mask(mask, shape_hw):
    """(omega, softness): omega is a bool (rows, cols) array, True where anything is to be
    filled; softness is None for a binary mask, else the float degree of damage in [0, 1].
    A colour mask counts by its brightest colour channel, alpha ignored (mask_plane: the
    command line's rule). A bool mask is used as is (no copy)."""
    refuse_path(mask, "mask")
    m = np.asarray(mask)
    if m.dtype != bool and not (np.issubdtype(m.dtype, np.number)):
        raise InputError(
            f"mask has dtype {m.dtype}; give a bool or numeric array (nonzero = inpaint)"
        )
    if m.ndim == 3 and m.shape[:2] == tuple(shape_hw):
        m = mask_plane(m)
    if m.shape != tuple(shape_hw):
        raise InputError(
            f"mask shape {m.shape} does not match the image's height and width {tuple(shape_hw)}; "
            "give a (rows, columns) mask of the same size as the image"
        )
    if m.dtype == bool:
        return m, None
    if not np.issubdtype(m.dtype, np.floating):
        return m != 0, None
    lo, hi = m.min(), m.max()  # NaN propagates into both
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise InputError(
            "mask contains NaN or infinite values; a float mask is the degree of "
            "damage in [0, 1] (0 keep, 1 inpaint)"
        )
    if lo < 0 or hi > 1:
        raise InputError(
            f"float mask values lie in [{lo:g}, {hi:g}], outside [0, 1]; a float mask "
            "is the degree of damage (0 keep, 1 inpaint): rescale it, or pass a bool "
            "mask (mask != 0)"
        )
    omega = m > 0
    soft = bool(((m > 0) & (m < 1)).any())
    return omega, (m if soft else None)


def prepare(image, mask, channel_axis, alpha):
    """(array, planes view (nc, ny, nx), omega, softness, layout, alpha): validation and the
    [0, 1] scaling, without a float copy of the image (boxes are converted one at a time)."""
    array = as_image(image, allow_nan=True)
    axis = check_channel_axis(array.ndim, channel_axis)
    planes = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
    floating = np.issubdtype(array.dtype, np.floating)
    finite = np.isfinite(planes).all(axis=0) if floating else None
    softness = None
    if mask is None:
        if finite is None:
            raise InputError(
                "mask=None fills the NaN pixels of a float image, but this image is "
                f"{array.dtype}; "
                "pass a mask (nonzero where to inpaint)"
            )
        omega = ~finite
    else:
        omega, softness = as_mask(mask, planes.shape[1:])
        if finite is not None and not finite[~omega].all():
            raise InputError(
                f"image has {int((~finite[~omega]).sum())} NaN or infinite pixels outside the "
                "mask; "
                "include them in the mask, or pass mask=None to fill every NaN pixel"
            )
        partly = None if softness is None else (softness > 0) & (softness < 1)
        if partly is not None and finite is not None and not finite[partly].all():
            raise InputError(
                "image has NaN or infinite pixels where the soft mask is below 1; "
                "a partly damaged pixel needs its observed value (set the mask to 1 "
                "there)"
            )
    nc = planes.shape[0]
    if alpha is None:
        alpha = axis is not None and nc == 4
    if alpha and nc < 2:
        raise InputError("alpha=True needs at least two channels (the last one is the alpha)")
    if alpha and finite is not None and not np.isfinite(planes[-1]).all():
        raise InputError(
            "the alpha channel (the last one) holds NaN or infinite values, and only the colour "
            "channels are inpainted; fix the alpha channel first, or pass alpha=False"
        )
    if array.dtype == bool or np.issubdtype(array.dtype, np.integer):
        offset, scale = integer_range(array.dtype)
    else:
        where = finite & ~omega if omega.any() and not omega.all() else finite
        if where.any():
            lo = float(np.min(planes, where=where[None], initial=np.inf))
            hi = float(np.max(planes, where=where[None], initial=-np.inf))
        else:
            lo, hi = 0.0, 1.0
        offset, scale = value_range(lo, hi)
    layout = ImageLayout(array.shape, array.dtype, axis, offset, scale)
    return array, planes, omega, softness, layout, bool(alpha)


def check_colour(colour: str, ncolour: int) -> None:
    if colour not in COLOUR_MODELS:
        raise InputError(f"colour must be one of {', '.join(COLOUR_MODELS)}, not {colour!r}")
    if colour == "rho-phi-psi" and ncolour != 3:
        raise InputError(
            f"colour='rho-phi-psi' needs 3 colour channels (R, G, B), the image has {ncolour}; "
            "use colour='channels'"
        )
