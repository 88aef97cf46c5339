"""Inpainting on implicit surfaces (thesis 5.3): data missing over part of a surface (vertex
colours or a scalar on a mesh, or data on an ImplicitSurface's band) filled by a PDE written
intrinsically, as chapter 4 writes the other flows.

The hole is the set of band cells whose closest point lies in the missing region. Only its
cells are stepped and re-extended (kernels/surface/inpaint.cl, extend.cl's extend_cp on the
hole's share of the band lists); the known cells keep their data, extended along the
normals, as the Dirichlet condition.

- 'harmonic': the Laplace-Beltrami equation in the hole, appendix E's discrete operator
  (the average of its two complementary one-sided choices), solved by Chebyshev's
  semi-iterative method: its iterations grow as 1/h, not 1/h^2 as the heat flow's would.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

import numpy as np
import pyopencl.array as cla

from .._progress import progress_range
from ..errors import InputError
from ..fields import IndexList
from .band import extend_defines
from .implicit import ImplicitSurface
from .mesh_sdf import load_mesh

KERNEL_FILES = ("surface/inpaint.cl", "surface/extend.cl")
METHODS = ("harmonic",)

# Upper end of the spectrum of -LB (grid units) that Chebyshev's method assumes: the 7-point
# Laplacian's is 12; the projection only lowers it, the tricubic re-extension may lift it a
# little (docs/surface.md measures it by power iteration on a sphere and a torus).
SPECTRUM_TOP = 13.0


@dataclass
class SurfaceInpaintInfo:
    """What a surface inpainting run did.

    Parameters
    ----------
    method : str
        The method.
    iterations : int
        Steps run.
    change : float
        The last step's largest change at the hole's nodes, relative to the known data's
        range (the run stops once it is below tol).
    hole_cells : int
        Band cells in the hole.
    seconds : float
        Wall time of the fill on the device (upload to read-back).
    """

    method: str
    iterations: int
    change: float
    hole_cells: int
    seconds: float


def _sub_list(q, indices: np.ndarray) -> IndexList:
    return IndexList(cla.to_device(q, np.ascontiguousarray(indices, np.int32)), len(indices))


class HoleLists:
    """The hole's share of a surface's band lists, built once per (surface, hole): its nodes
    (stepped), its reach cells and extension cells with their closest-point stencils
    (re-extended)."""

    def __init__(self, surf: ImplicitSurface, hole_padded: np.ndarray):
        q = surf.runtime.queue

        def select(band):
            cells = band.indices.get()[: band.n]
            return cells, hole_padded[cells]

        nodes, keep = select(surf.node_band)
        self.nodes = _sub_list(q, nodes[keep])
        self.reach = self._stencils(q, surf.reach_band, *surf.reach_stencils, hole_padded)
        self.ext = self._stencils(q, surf.ext_band, surf.cp_base, surf.cp_frac, hole_padded)

    @staticmethod
    def _stencils(q, band, base, frac, hole_padded):
        cells = band.indices.get()[: band.n]
        keep = hole_padded[cells]
        sub_frac = np.ascontiguousarray(frac.get()[:, : band.n][:, keep])
        return (
            _sub_list(q, cells[keep]),
            cla.to_device(q, np.ascontiguousarray(base.get()[: band.n][keep])),
            cla.to_device(q, sub_frac if sub_frac.size else np.zeros((3, 1), sub_frac.dtype)),
        )


def _hole_area(surf: ImplicitSurface, hole_cells: int) -> float:
    """The hole's area in grid units (cells^2): the band holds about 2 * outer cells along
    each normal, so its cell count over that is the area it covers."""
    return hole_cells / (2.0 * surf.outer)


def chebyshev_bounds(surf: ImplicitSurface, hole_cells: int) -> tuple[float, float]:
    """(a, b) bounding the spectrum of -LB on the hole (grid units): a from Faber-Krahn (no
    region of the hole's area has a lower first Dirichlet eigenvalue than the disc's,
    j0^2 pi / area), halved for curvature and the discrete boundary; b = SPECTRUM_TOP."""
    area = max(_hole_area(surf, hole_cells), 1.0)
    return 0.5 * 2.404825557695773**2 * math.pi / area, SPECTRUM_TOP


def fill_band(
    surf: ImplicitSurface,
    values: np.ndarray,
    hole: np.ndarray,
    *,
    method: str = "harmonic",
    tol: float = 1e-5,
    max_iterations: int | None = None,
    check_every: int = 50,
    progress: bool | None = None,
) -> tuple[np.ndarray, SurfaceInpaintInfo]:
    """The fill on the band: values (channels, n) in band form, hole (n,) bool; returns the
    filled (channels, n) float64 and the info."""
    if method not in METHODS:
        raise InputError(f"unknown surface inpainting method {method!r}; use {', '.join(METHODS)}")
    start = time.perf_counter()
    g, q = surf.grid, surf.runtime.queue
    nc, n = values.shape
    values = np.array(values, dtype=np.float64)
    known = ~hole
    if not known.any():
        raise InputError("every cell of the surface is missing: nothing to fill the hole from")
    if not hole.any():
        info = SurfaceInpaintInfo(method, 0, 0.0, 0, time.perf_counter() - start)
        return values, info
    lo, hi = values[:, known].min(axis=1), values[:, known].max(axis=1)
    span = float(max((hi - lo).max(), 1e-30))
    # start from the known data's mean: any start converges, Chebyshev's rate does not
    # depend on it
    values[:, hole] = values[:, known].mean(axis=1)[:, None]
    padded_cells = surf.band.cells()[1]
    hole_padded = np.zeros(g.volume, bool)
    hole_padded[padded_cells[hole]] = True
    lists = HoleLists(surf, hole_padded)
    cur = cla.to_device(q, surf.band.padded_from(values))
    x, prev = cur.copy(), cur.copy()
    defines = {"NC": nc}
    step = g.kernel("surface/inpaint.cl", "inpaint_harmonic_step", **defines)
    extend = g.kernel("surface/extend.cl", "extend_cp", **extend_defines(surf.interp, nc))
    change = cla.zeros(q, (nc, max(lists.nodes.n, 1)), g.dtype)
    strides = g.strides()

    def extend_to(band, base, frac, src, dst):
        g.launch_list(extend, band, src.data, dst.data, base.data, frac.data, *strides)

    def largest_change() -> float:
        return float(change.get()[:, : lists.nodes.n].max()) / span

    a, b = chebyshev_bounds(surf, int(hole.sum()))
    theta, delta = (b + a) / 2, (b - a) / 2
    sigma = theta / delta
    if max_iterations is None:
        # Chebyshev's error bound 2 ((sqrt(k) - 1) / (sqrt(k) + 1))^m, k = b / a, down to tol,
        # twice over for a's estimate
        kappa = b / a
        rate = (math.sqrt(kappa) - 1) / (math.sqrt(kappa) + 1)
        max_iterations = int(2 * math.ceil(math.log(tol / 2) / math.log(rate))) + check_every
    rho = 1 / sigma
    iterations, last = 0, float("inf")
    for k in progress_range(progress, max_iterations, "surface inpaint", leave=False, queue=q):
        if k == 0:
            mom, gain = 0.0, 1 / theta
        else:
            rho_new = 1 / (2 * sigma - rho)
            mom, gain = rho_new * rho, 2 * rho_new / delta
            rho = rho_new
        g.launch_list(step, lists.nodes, cur.data, x.data, prev.data, surf.psi_dev.data,
                      g.scalar(mom), g.scalar(gain), change.data, *strides, channels=nc)
        extend_to(*lists.reach, x, cur)
        iterations = k + 1
        if iterations % check_every == 0:
            last = largest_change()
            if last < tol:
                break
    last = largest_change()
    # the fill on the whole band's hole cells: their closest points' values from x
    extend_to(*lists.ext, x, cur)
    out = cur.get().reshape(nc, -1)[:, padded_cells]
    out[:, known] = values[:, known]
    info = SurfaceInpaintInfo(method, iterations, last, int(hole.sum()),
                              time.perf_counter() - start)
    return out.astype(np.float64), info
