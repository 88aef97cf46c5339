"""Data on a surface read at world points, by the interpolation of the closest-point
re-extension (tricubic or trilinear), on the device."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike

from ..errors import InputError
from .band import NODE_REACH, extend_defines, interp_code

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/extend.cl",)

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


def world_to_index(surf: ImplicitSurface, points: ArrayLike) -> np.ndarray:
    """(n, 3) world points to padded index coordinates (3, n) of the surface's grid."""
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"points must be an (n, 3) array of x, y, z, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise InputError("points contain NaN or infinite values")
    return ((p - surf.origin) / surf.spacing + surf.grid.ghost).T


def sample(
    surf: ImplicitSurface, u: ArrayLike, points: ArrayLike, interpolation: str = "tricubic"
) -> np.ndarray:
    """Values of u (dense or in band form) at world points (n, 3) within the interpolation's
    reach of the surface: shape (n,) for scalar u, (n, channels) else."""
    u = np.asarray(u)
    band_form = surf.band.form_channels(u) is not None
    data = surf.band.padded_from(u) if band_form else surf.band.as_channels(u)
    scalar = u.ndim == (1 if band_form else 3)
    idx = world_to_index(surf, points)
    code = interp_code(interpolation)
    g = surf.grid
    n = idx.shape[1]
    if n == 0:
        return np.zeros((0,) if data.shape[0] == 1 and scalar else (0, data.shape[0]))
    lo = g.ghost
    hi = np.array([g.nx, g.ny, g.nz]) + g.ghost - 1
    if np.any(idx < lo - 1e-9) or np.any(idx.T > hi + 1e-9):
        raise InputError("some points lie outside the surface's grid")
    dist = np.abs(_sample_raw(surf, surf.psi_dev, idx, 1, 1)[0]) / surf.spacing
    reach = surf.outer - NODE_REACH[code]
    if np.any(dist > reach + 1e-6):
        raise InputError(
            f"some points lie {dist.max():.2f} cells from the surface; sample() reads "
            f"data within {reach:.2f} cells of it (project the points onto the surface)"
        )
    if band_form:
        surf.runtime.check_alloc(data.nbytes, "surface volume")
        dev = cla.to_device(surf.runtime.queue, data)
    else:
        dev = g.upload(data)
    out = _sample_raw(surf, dev, idx, data.shape[0], code)
    return out[0] if scalar else out.T


def _sample_raw(
    surf: ImplicitSurface, dev: cla.Array, idx: np.ndarray, nc: int, code: int
) -> np.ndarray:
    g, q = surf.grid, surf.runtime.queue
    n = idx.shape[1]
    pts = [cla.to_device(q, np.ascontiguousarray(idx[a], g.dtype)) for a in range(3)]
    out = cla.empty(q, (nc, n), g.dtype)
    g.kernel("surface/extend.cl", "extend_sample_points", **extend_defines(code, nc))(
        q,
        *surf.runtime.items(n),
        dev.data,
        pts[0].data,
        pts[1].data,
        pts[2].data,
        np.int32(n),
        out.data,
        *g.strides(),
        *g.padded_dims(),
        np.int32(g.volume),
    )
    return out.get().astype(np.float64)
