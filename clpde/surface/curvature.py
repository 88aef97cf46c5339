"""The surface's principal curvatures and curvature directions, on the extension band."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyopencl.array as cla

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/shape.cl",)

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


def principal_directions(
    surf: ImplicitSurface,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Principal curvature directions and curvatures of `surf` on the extension band:
    the implementation of ImplicitSurface.principal_directions, which documents the results."""
    g, q = surf.grid, surf.runtime.queue
    band = surf.ext_band
    n = max(band.n, 1)
    dirs = cla.empty(q, (6, n), g.dtype)
    curv = cla.empty(q, (2, n), g.dtype)
    g.launch_list(
        g.kernel("surface/shape.cl", "shape_principal_directions"),
        band,
        surf.psi_dev.data,
        g.scalar(1 / surf.spacing),
        dirs.data,
        curv.data,
        *g.strides(),
    )
    idx = band.indices.get()[: band.n]
    vol = np.zeros((8, g.volume))
    vol[:6, idx] = dirs.get()[:, : band.n]
    vol[6:, idx] = curv.get()[:, : band.n]
    vol = g.interior(vol.reshape((8,) + g.padded_shape))
    return vol[0:3].copy(), vol[3:6].copy(), vol[6:8].copy()
