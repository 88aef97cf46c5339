"""Filling film damage from the neighbouring frames, with spatial inpainting where they fail.

Per damaged frame: optical flow to each neighbour up to `radius` frames away, estimated with
the damage of both frames masked out; each neighbour warped onto the frame, its flicker
corrected by a gain and offset fitted on the clean pixels; every damaged pixel copies the
value of one neighbour that sees it clean, chosen by how well each neighbour matches the
frame around the pixel and then as the medoid of the remaining candidates
(kernels/film/fill.cl). Copying one real frame's value keeps its grain. Pixels no neighbour
sees clean (a scratch at the same place in every neighbour, a region revealed by motion)
are filled by `clpde.inpaint`, with grain of the frame's measured level added so that
they do not show as smooth patches.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike

from .._progress import Progress, progress_bar
from ..errors import InputError
from ..imagedata import grow_mask
from ..inpainting.api import inpaint
from ..planar.rof import _noise_std
from ._compensate import Compensator
from ._frames import film_masks, film_planes, grey

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/fill.cl",)

# A neighbour's warped place counts as clean below this degree of damage (the bilinear
# warp of a bool mask spreads it over a pixel's rim).
_CLEAN = 0.01
# The half width of the window on which neighbours are compared with the frame.
_RADIUS_MATCH = 4


def _spatial(frame: np.ndarray, hole: np.ndarray, options: dict) -> np.ndarray:
    """clpde.inpaint on one (C, H, W) [0, 1] frame."""
    image = frame[0] if frame.shape[0] == 1 else np.moveaxis(frame, 0, -1)
    axis = None if frame.shape[0] == 1 else -1
    out = inpaint(image.astype(np.float32), hole, channel_axis=axis, **options)
    out = np.asarray(out, np.float32)
    # inpaint scales a float image by its own range and returns that range: keep [0, 1]
    return out[np.newaxis] if axis is None else np.moveaxis(out, -1, 0)


def inpaint_video(
    frames: ArrayLike,
    masks: ArrayLike,
    *,
    channel_axis: int | None = None,
    radius: int = 3,
    grain: bool = True,
    seed: int = 0,
    spatial: dict | None = None,
    device: str | int | None = None,
    return_unfilled: bool = False,
    progress: Progress = None,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Fill damaged pixels of film frames from the neighbouring frames that see them clean.

    For each frame with damage, dense optical flow to each neighbour up to `radius` frames
    away is estimated on the device with the damage masked out; each damaged pixel copies
    the flicker-corrected value of the neighbour that best agrees with the frame around it
    (the medoid of the agreeing candidates), all channels from the same frame, so the grain
    stays. Where no neighbour sees a pixel clean, `clpde.inpaint`'s default fills it, with
    grain of the frame's measured level added (``grain=True``). Neighbours are read as
    given, never as already filled, so each frame's result depends only on its window.

    Parameters
    ----------
    frames : array, (T, H, W) or (T, H, W, C)
        Integer or float frames, never modified. One image (H, W) (or (H, W, C) with
        channel_axis) is filled spatially.
    masks : array, (T, H, W)
        The damage per frame: bool, nonzero integers, or floats in [0, 1] (soft: the output
        blends fill and frame by the degree of damage), as in `clpde.inpaint`.
    channel_axis : int, optional
        The channel axis of colour frames (e.g. -1).
    radius : int
        Neighbour frames each side to fill from.
    grain : bool
        Add grain of the measured level where the spatial fill had to be used.
    seed : int
        Seed of that grain, so runs repeat exactly.
    spatial : dict, optional
        Keyword arguments for `clpde.inpaint` where the neighbours do not help.
    device : str or int, optional
        As for `clpde.diffuse`.
    return_unfilled : bool
        Also return the bool (T, H, W) mask of the pixels the spatial fill took.
    progress : bool or callable, optional
        As for `clpde.inpaint`: a bar over the frames, or a callable
        ``progress(done, total)`` that may stop the run by raising.

    Returns
    -------
    ndarray
        The restored frames, the input's shape and dtype; with return_unfilled, also the
        pixels no neighbour filled.

    Raises
    ------
    InputError
        Masks of the wrong count or size, frames clpde cannot use, a bad parameter.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> from scipy.ndimage import gaussian_filter
    >>> scene = gaussian_filter(np.random.default_rng(0).random((64, 96)), 2)
    >>> clean = np.stack([scene[:, t:t + 64] for t in range(5)])  # a pan
    >>> dirty = clean.copy(); dirty[2, 20:30, 20:30] = 1.0
    >>> masks = np.zeros(clean.shape, bool); masks[2, 20:30, 20:30] = True
    >>> out = clpde.inpaint_video(dirty, masks)
    >>> bool(np.abs(out[2, 20:30, 20:30] - clean[2, 20:30, 20:30]).max() < 0.01)
    True
    """
    planes, layout = film_planes(frames, channel_axis)
    T, C, ny, nx = planes.shape
    m = film_masks(masks, (T, ny, nx), layout.photo)
    if not isinstance(radius, (int, np.integer)) or radius < 1:
        raise InputError(f"radius must be a positive integer, not {radius!r}")
    options = {} if spatial is None else dict(spatial)
    G = grey(planes)
    out = planes.copy()
    unfilled = np.zeros((T, ny, nx), bool)
    damaged = [t for t in range(T) if m[t].any()]
    # temporal fills first, then the spatial fallback: one unit per damaged frame for each
    bar = progress_bar(progress, 2 * len(damaged), "clpde inpaint_video", unit="frame")
    if T > 1 and damaged:
        comp = Compensator(G, device, colour=planes, masks=m)
        rt, q = comp.rt, comp.q
        k_fill = rt.kernel("film/fill.cl", "temporal_fill")
        g, loc = rt.items(nx, ny)
        res = cla.empty(q, (C, ny, nx), np.float32)
        left = cla.empty(q, (ny, nx), np.float32)
        for t in damaged:
            offs = [k for k in range(-radius, radius + 1) if k != 0 and 0 <= t + k < T]
            nb = comp.neighbours(t, offs, want_colour=True)
            sigma = max(_noise_std(G[t].astype(np.float64)), 0.5 / 255)
            # nearer frames first on ties, then the earlier one
            dist = np.array([abs(k) + (0.5 if k > 0 else 0.0) for k in offs], np.float32)
            k_fill(
                q,
                g,
                loc,
                comp.colour[t].data,
                comp.grey[t].data,
                comp.mask_dev[t].data,
                nb.colour.data,
                nb.grey.data,
                nb.mask.data,
                nb.valid.data,
                cla.to_device(q, nb.gain).data,
                cla.to_device(q, nb.offset).data,
                cla.to_device(q, dist).data,
                np.int32(len(offs)),
                np.int32(C),
                np.float32(sigma),
                np.int32(_RADIUS_MATCH),
                np.float32(_CLEAN),
                res.data,
                left.data,
                np.int32(nx),
                np.int32(ny),
            )
            out[t] = res.get()
            unfilled[t] = left.get() > 0.5
            bar.update(1)
    elif damaged:
        unfilled = m > 0
    rng = np.random.default_rng(seed)
    for t in range(T):
        if t in damaged:
            bar.update(1 if T > 1 else 2)
        if not unfilled[t].any():
            continue
        # one pixel more, so the spatial fill starts from pixels the frame holds clean
        hole = grow_mask(unfilled[t], 1.0) & (m[t] > 0) | unfilled[t]
        filled = _spatial(out[t], hole, options)
        soft = m[t][np.newaxis]
        blend = soft * filled + (1.0 - soft) * planes[t]
        if grain:
            sigma = _noise_std(G[t].astype(np.float64))
            blend = blend + (sigma * soft * rng.standard_normal((1, ny, nx))).astype(np.float32)
        out[t] = np.where(hole[np.newaxis], blend, out[t])
    bar.close()
    restored = layout.restore(out)
    if return_unfilled:
        return restored, (unfilled[0] if layout.photo else unfilled)
    return restored
