"""Image pyramids for multiresolution inpainting (thesis section 3.3.3).

A coarse level halves each side. A coarse pixel is known only when all four fine pixels
under it are known (its value is their mean); otherwise it is part of the coarse Omega.
The converged coarse result, upsampled bilinearly, is the start inside the next finer Omega
(plus the extension into Omega of its mismatch with the fine level's known pixels, so that
the start joins the border without seams: clpde.inpaint's coarse_start="corrected").
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from skimage.transform import resize

COARSEST_SIDE = 16  # never coarsen below this many pixels per side


def hole_half_width(omega: np.ndarray) -> float:
    """Largest distance from a pixel of Omega to the nearest known pixel."""
    return float(ndimage.distance_transform_edt(omega).max()) if omega.any() else 0.0


MAX_AUTO_LEVELS = 2


def auto_levels(omega: np.ndarray, target_half_width: float = 8.0) -> int:
    """One level for thin masks (half-width <= `target_half_width`: text, scratches), two
    for thicker ones.

    Chosen with the corrected coarse start (inpaint's coarse_start="corrected") on the
    benchmark's blobs and thick holes: more levels carry structure from further away but
    blur it, and two is the best on average for both, though not on every image
    (docs/inpainting.md, Multiresolution, has the table).
    """
    width = hole_half_width(omega)
    return 1 if width <= target_half_width else MAX_AUTO_LEVELS


def downsample(data: np.ndarray, omega: np.ndarray):
    """(nc, ny, nx) data and its Omega -> the next coarser level (sizes rounded up)."""
    nc, ny, nx = data.shape
    py, px = ny % 2, nx % 2
    data = np.pad(data, ((0, 0), (0, py), (0, px)), mode="edge")
    omega = np.pad(omega, ((0, py), (0, px)), mode="edge")
    cy, cx = data.shape[1] // 2, data.shape[2] // 2
    blocks = data.reshape(nc, cy, 2, cx, 2)
    coarse = blocks.mean(axis=(2, 4))
    coarse_omega = omega.reshape(cy, 2, cx, 2).any(axis=(1, 3))
    coarse[:, coarse_omega] = 0.0
    return coarse, coarse_omega


def upsample(data: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(nc, cy, cx) -> (nc, ny, nx) by bilinear interpolation (the inverse geometry of
    `downsample`: upsample to twice the size, then drop the padded row or column)."""
    nc, cy, cx = data.shape
    fine = resize(data, (nc, 2 * cy, 2 * cx), order=1, mode="edge", anti_aliasing=False)
    return fine[:, : shape[0], : shape[1]]


def pyramid(data: np.ndarray, omega: np.ndarray, levels: int):
    """[(data, omega)] from fine (index 0) to coarse; stops early if a level has no known
    pixel left or gets too small."""
    out = [(data, omega)]
    for _ in range(levels - 1):
        d, o = out[-1]
        if min(o.shape) // 2 < COARSEST_SIDE // 2:
            break
        cd, co = downsample(d, o)
        if co.all():
            break
        out.append((cd, co))
    return out
