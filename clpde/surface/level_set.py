"""PDEs run to a steady state on the band around a surface: Sussman's reinitialisation, which
makes psi a signed distance, and the upwind extension of data along the normals (section 4.2).
The closest-point re-extension the flows use instead is in storage.py."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._progress import progress_range
from .band import extend_defines
from .storage import BandFlow

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/extend.cl", "surface/reinit.cl")

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


def reinitialized_psi(
    surf: ImplicitSurface, iterations: int | None = None, progress: bool | None = None
) -> np.ndarray:
    """The surface's psi made a signed distance (Sussman's PDE with Russo-Smereka's subcell
    fix, on the device), without touching the surface: float64 (nz, ny, nx)."""
    g = surf.grid
    reach = surf.outer + 4.0
    r = 0.3
    steps = int(np.ceil(reach / r)) if iterations is None else int(iterations)
    everywhere = g.band(surf.psi_dev, np.inf)
    phi0 = surf.psi_dev
    cur, nxt = phi0.copy(), phi0.copy()
    kernel = g.kernel("surface/reinit.cl", "reinit_step")
    for _ in progress_range(progress, steps, "reinitialise", leave=False, queue=g.runtime.queue):
        g.launch_list(
            kernel,
            everywhere,
            cur.data,
            nxt.data,
            phi0.data,
            g.scalar(r),
            g.scalar(1 / surf.spacing),
            *g.strides(),
        )
        cur, nxt = nxt, cur
    return g.download(cur)[0].astype(np.float64)


def slope_at_surface(psi: np.ndarray, spacing: float) -> float:
    """Median |grad psi| over the cells next to a sign change (1 if there are none)."""
    g = np.gradient(psi, spacing)
    slope = np.sqrt(g[0] ** 2 + g[1] ** 2 + g[2] ** 2)
    near = np.zeros(psi.shape, bool)
    for axis in range(3):
        a = np.moveaxis(psi, axis, 0)
        change = np.signbit(a[1:]) != np.signbit(a[:-1])
        n = np.moveaxis(near, axis, 0)
        n[1:] |= change
        n[:-1] |= change
    values = slope[near & (slope > 0)]
    return float(np.median(values)) if values.size else 1.0


def extend_by_pde(surf: ImplicitSurface, u: ArrayLike, iterations: int | None = None) -> np.ndarray:
    """Data extended off the surface by the upwind PDE of section 4.2,
    u_t + sign(psi) grad u . grad psi / |grad psi| = 0, run to a steady state in the band:
    in u's form (dense or band form) and float dtype."""
    # the PDE runs on the band lists in either storage (a one-off, not a flow's step)
    flow = BandFlow(surf, u, extend=False)
    g = surf.grid
    r = 0.5  # CFL: r (|a_x| + |a_y| + |a_z|) <= r sqrt(3) < 1
    steps = int(np.ceil(2 * surf.outer / r)) if iterations is None else int(iterations)
    defines = extend_defines(surf.interp, flow.nc)  # the re-extension's program
    kernel = g.kernel("surface/extend.cl", "extend_pde_step", **defines)
    for _ in range(steps):
        # cur -> tmp, then back: cells outside the band keep their values in both buffers
        for src, dst in ((flow.cur, flow.tmp), (flow.tmp, flow.cur)):
            g.launch_list(
                kernel,
                surf.ext_band,
                src.data,
                dst.data,
                surf.psi_dev.data,
                g.scalar(r),
                g.scalar(surf.spacing),
                *g.strides(),
            )
    return flow.result()
