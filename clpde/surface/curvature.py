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
    """Principal curvature directions and curvatures of the surface, extended along normals.

    Directions are defined up to sign, which the flows along them ignore (the flux (d.Pv)d is
    even in d); sample them at nodes rather than interpolating across sign flips.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.

    Returns
    -------
    major, minor : ndarray
        (3, nz, ny, nx) unit tangent fields (major = the larger curvature), computed at every
        cell of the extension band (constant along normals for a distance function); zeros
        off the band.
    curvatures : ndarray
        (2, nz, ny, nx): the larger and the smaller principal curvature.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, principal_directions
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> major, minor, curvatures = principal_directions(s)
    >>> on = np.abs(s.psi) < 0.05
    >>> bool(np.allclose(curvatures[:, on], 1.0, atol=0.1))   # a unit sphere: k1 = k2 = 1
    True
    """
    g, q = surf.grid, surf.runtime.queue
    band = surf.ext_band
    n = max(band.n, 1)
    dirs = cla.empty(q, (6, n), g.dtype)
    curv = cla.empty(q, (2, n), g.dtype)
    g.launch_list(
        g.kernel("surface/shape.cl", "principal_directions"),
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
