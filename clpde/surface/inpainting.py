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
- 'transport': from the harmonic fill, the thesis' transport of smoothness along isophotes
  (chapter 3, appendix A) with every derivative projected on the tangent plane, cycled with
  intrinsic curvature diffusion on the plane's schedule (TRANSPORT).

The command line's run (`clpde surface inpaint`) is `inpaint_file`.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike

from .._progress import progress_range
from ..errors import InputError
from ..fields import IndexList
from .band import extend_defines
from .implicit import ImplicitSurface
from .mesh_sdf import encloses_volume, load_mesh

if TYPE_CHECKING:
    import trimesh

    from ..runtime import DeviceLike

KERNEL_FILES = ("surface/inpaint.cl", "surface/extend.cl")
METHODS = ("harmonic", "transport")
# The transport's schedule, the plane's (clpde/inpainting/transport_params.py): A transport
# steps of dt, then B anisotropic diffusion steps of diffusion_dt, on data scaled to a range
# of 1 (the plane scales to [0, 1]; the transport's speed depends on the scale, not on a shift).
TRANSPORT = {"dt": 0.1, "transport_steps": 15, "diffusion_steps": 2, "diffusion_dt": 0.1}

# Upper end of the spectrum of -LB (grid units) that Chebyshev's method assumes: the 7-point
# Laplacian's is 12; the projection only lowers it, the tricubic re-extension may lift it a
# little (power iteration on a sphere gave 6.1-6.9: docs/surface.md).
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
        'harmonic': the error left, estimated from the last step's largest change at the
        hole's nodes and Chebyshev's rate, relative to the known data's range (the run stops
        once it is below tol). 'transport': the last transport step's largest change,
        relative to that range.
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


def _schedule(surf, hole_cells, nodes, tol, check_every, max_iterations):
    """Chebyshev's centre and half-width of the spectrum, its rate, and the step cap."""
    a, b = chebyshev_bounds(surf, hole_cells)
    # Chebyshev's error falls by rate = (sqrt(k) - 1) / (sqrt(k) + 1) a step, k = b / a: a
    # step of size c leaves about c / (1 - rate) to go
    kappa = b / a
    rate = (math.sqrt(kappa) - 1) / (math.sqrt(kappa) + 1)
    if nodes == 0:
        max_iterations = 0  # a hole between the nodes: its cells are the known nodes' extension
    elif max_iterations is None:
        # the bound 2 rate^m down to tol, twice over for a's estimate
        max_iterations = int(2 * math.ceil(math.log(tol / 2) / math.log(rate))) + check_every
    return (b + a) / 2, (b - a) / 2, rate, max_iterations


def _centred(surf, values, hole, padded_cells):
    """values scaled by their range and shifted by the mean of the hole's rim, with the
    shift and the range."""
    known = ~hole
    lo, hi = values[:, known].min(axis=1), values[:, known].max(axis=1)
    span = float(max((hi - lo).max(), 1e-30))
    # The data scaled by its range (the tolerances are relative, and the transport's speed
    # grows with the data's scale, as in the plane) and shifted by the mean of the hole's
    # rim, which is also the start in the hole: near the hole the values are then small,
    # and float32 keeps more of their digits (shifted by the range's low end, the fill's
    # error on a torus stalled at 2.5x its float64-limited value).
    rim = _zone(surf, padded_cells, hole, 2.0)[padded_cells] & known
    centre = values[:, rim if rim.any() else known].mean(axis=1)
    values = (values - centre[:, None]) / span
    return values, centre, span


def _chebyshev(theta: float, delta: float):
    """(momentum, gain) of each Chebyshev semi-iterative step for a spectrum in
    [theta - delta, theta + delta]; the three-term recurrence needs no stored history."""
    sigma = theta / delta
    rho = 1 / sigma
    yield 0.0, 1 / theta
    while True:
        rho_new = 1 / (2 * sigma - rho)
        yield rho_new * rho, 2 * rho_new / delta
        rho = rho_new


def fill_band(
    surf: ImplicitSurface,
    values: np.ndarray,
    hole: np.ndarray,
    *,
    method: str = "harmonic",
    tol: float = 1e-5,
    max_iterations: int | None = None,
    check_every: int = 50,
    max_cycles: int = 200,
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
    padded_cells = surf.band.cells()[1]
    given = values.copy()
    values, centre, span = _centred(surf, values, hole, padded_cells)
    values[:, hole] = 0.0
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
        return float(change.get()[:, : lists.nodes.n].max(initial=0.0))

    theta, delta, rate, max_iterations = _schedule(
        surf, int(hole.sum()), lists.nodes.n, tol, check_every, max_iterations
    )
    iterations, last = 0, float("inf")
    steps = progress_range(progress, max_iterations, "surface inpaint", leave=False, queue=q)
    for k, (mom, gain) in zip(steps, _chebyshev(theta, delta), strict=False):  # endless weights
        g.launch_list(
            step,
            lists.nodes,
            cur.data,
            x.data,
            prev.data,
            surf.psi_dev.data,
            g.scalar(mom),
            g.scalar(gain),
            change.data,
            *strides,
            channels=nc,
        )
        extend_to(*lists.reach, x, cur)
        iterations = k + 1
        if iterations % check_every == 0:
            last = largest_change() / (1 - rate)
            if last < tol:
                break
    last = largest_change() / (1 - rate)
    if method == "transport" and lists.nodes.n:
        bounds = np.stack([values[:, known].min(axis=1), values[:, known].max(axis=1)], 1)
        cycles, last = _transport(
            surf,
            bounds,
            lists,
            cur,
            x,
            change,
            nc,
            padded_cells,
            hole,
            extend_to,
            max_cycles,
            tol,
            progress,
        )
        iterations += cycles * (TRANSPORT["transport_steps"] + TRANSPORT["diffusion_steps"])
    # the fill on the whole band's hole cells: their closest points' values from x
    extend_to(*lists.ext, x, cur)
    out = cur.get().reshape(nc, -1)[:, padded_cells].astype(np.float64)
    out = out * span + centre[:, None]
    out[:, known] = given[:, known]
    info = SurfaceInpaintInfo(
        method, iterations, last, int(hole.sum()), time.perf_counter() - start
    )
    return out, info


def _zone(surf: ImplicitSurface, padded_cells, hole, cells: float) -> np.ndarray:
    """Padded mask of the band cells whose closest point lies within `cells` grid cells of
    a hole cell's closest point."""
    from scipy.spatial import cKDTree

    cp = surf.band_closest_points()
    near = cKDTree(cp[hole]).query(cp, distance_upper_bound=cells * surf.spacing)[0]
    zone = np.zeros(surf.grid.volume, bool)
    zone[padded_cells[np.isfinite(near)]] = True
    return zone


def _transport(
    surf,
    bounds,
    lists,
    cur,
    x,
    change,
    nc,
    padded_cells,
    hole,
    extend_to,
    max_cycles,
    tol,
    progress,
):
    """The transport cycles from the harmonic fill in cur / x: (cycles, last change). bounds
    (channels, 2): each channel's known range, to which the transport step is clamped.

    L is needed at the hole's nodes' neighbours: it is computed at the nodes within 9 cells
    of the hole (lb_cell reads the reach band around them) and re-extended over the reach
    cells within 3, which hold every neighbour of a hole node and whose closest points'
    stencils stay within the 9."""
    g, q = surf.grid, surf.runtime.queue
    strides = g.strides()
    lap_nodes = HoleLists(surf, _zone(surf, padded_cells, hole, 9.0)).nodes
    lap_reach = HoleLists(surf, _zone(surf, padded_cells, hole, 3.0)).reach
    lap, lap_ext = cla.zeros_like(cur), cla.zeros_like(cur)
    kernel = {
        "lap": g.kernel("surface/inpaint.cl", "inpaint_lap", NC=nc),
        "transport_step": g.kernel("surface/inpaint.cl", "inpaint_transport_step", NC=nc),
        "diffusion_step": g.kernel("surface/inpaint.cl", "inpaint_diffusion_step", NC=nc),
    }
    dt, ddt = g.scalar(TRANSPORT["dt"]), g.scalar(TRANSPORT["diffusion_dt"])
    eps2, e2 = g.scalar(1e-10), g.scalar(1e-8)
    psi = surf.psi_dev.data
    bounds_dev = cla.to_device(q, np.ascontiguousarray(bounds, g.dtype).reshape(-1))
    last, cycles = float("inf"), 0
    for _ in progress_range(progress, max_cycles, "surface transport", leave=False, queue=q):
        cycles += 1
        for _ in range(TRANSPORT["transport_steps"]):
            g.launch_list(kernel["lap"], lap_nodes, cur.data, lap.data, psi, *strides, channels=nc)
            extend_to(*lap_reach, lap, lap_ext)
            g.launch_list(
                kernel["transport_step"],
                lists.nodes,
                cur.data,
                x.data,
                lap_ext.data,
                psi,
                dt,
                eps2,
                g.scalar((0.9 * surf.spacing) ** 2),
                bounds_dev.data,
                change.data,
                *strides,
                channels=nc,
            )
            extend_to(*lists.reach, x, cur)
        for _ in range(TRANSPORT["diffusion_steps"]):
            g.launch_list(
                kernel["diffusion_step"],
                lists.nodes,
                cur.data,
                x.data,
                psi,
                ddt,
                e2,
                *strides,
                channels=1,
            )
            extend_to(*lists.reach, x, cur)
        last = float(change.get()[:, : lists.nodes.n].max(initial=0.0))
        if last < tol:
            break
    return cycles, last


def _surface_form(surf: ImplicitSurface, values, missing):
    """(values (channels, n), hole (n,), restore) for data on a surface, dense or band form;
    restore turns the filled band form back into the input's form."""
    values = np.asarray(values)
    missing = np.asarray(missing)
    if missing.dtype != bool:
        raise InputError(
            f"missing must be a boolean array (True where data is missing), not {missing.dtype}"
        )
    if not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
        raise InputError(f"values must hold real numbers, not {values.dtype}")
    dtype = values.dtype if np.issubdtype(values.dtype, np.floating) else np.float64
    band_form = surf.band.form_channels(values) is not None
    if band_form:
        if missing.shape != (surf.ext_band.n,):
            raise InputError(
                f"missing must have shape ({surf.ext_band.n},), the band form of values, got "
                f"{missing.shape}"
            )
        vals, hole = values.reshape(-1, surf.ext_band.n), missing
    else:
        if missing.shape != surf.shape:
            raise InputError(
                f"missing must have the surface's grid shape {surf.shape}, got {missing.shape}"
            )
        vals = surf.band_values(values).reshape(-1, surf.ext_band.n)
        hole = surf.band_values(missing)
    known = ~hole
    if not np.all(np.isfinite(vals[:, known])):
        raise InputError("values contain NaN or infinite entries outside the missing region")
    vals = np.where(hole[None], 0.0, vals)  # what the hole held is never read

    def restore(out):
        out = out.astype(dtype)
        if band_form:
            return out[0] if values.ndim == 1 else out
        dense = np.array(values, dtype=dtype, copy=True)
        flat = dense.reshape(-1, int(np.prod(surf.shape)))
        flat[:, surf.band_indices()] = out
        return dense

    return vals, hole, restore


def vertex_mask(missing, vertices: int) -> np.ndarray:
    """A per-vertex boolean mask from a boolean mask or integer vertex indices."""
    missing = np.asarray(missing)
    if missing.dtype == bool:
        if missing.shape != (vertices,):
            raise InputError(
                f"a boolean missing mask needs one entry per mesh vertex ({vertices}), got "
                f"shape {missing.shape}"
            )
        return missing
    if missing.ndim != 1 or not np.issubdtype(missing.dtype, np.integer):
        raise InputError(
            "missing must be a boolean mask with one entry per vertex, or a 1D array of "
            f"integer vertex indices, not {missing.dtype} of shape {missing.shape}"
        )
    if missing.size and (missing.min() < 0 or missing.max() >= vertices):
        raise InputError(
            f"missing vertex indices must lie in 0..{vertices - 1}, got {missing.min()}.."
            f"{missing.max()}"
        )
    mask = np.zeros(vertices, bool)
    mask[missing] = True
    return mask


def mesh_values(mesh, values) -> np.ndarray:
    """The data on a mesh's vertices: `values` (vertices,) or (vertices, channels) checked,
    or the mesh's RGB vertex colours (uint8) when values is None."""
    if values is None:
        if getattr(mesh.visual, "kind", None) != "vertex":
            raise InputError(
                "the mesh has no vertex colours: give the values to fill (one per vertex; "
                "--values FILE on the command line)"
            )
        return np.asarray(mesh.visual.vertex_colors)[:, :3]
    values = np.asarray(values)
    if values.ndim not in (1, 2) or values.shape[0] != len(mesh.vertices):
        raise InputError(
            f"values must have one row per mesh vertex ({len(mesh.vertices)}): shape "
            f"(vertices,) or (vertices, channels), got {values.shape}"
        )
    if not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
        raise InputError(f"values must hold real numbers, not {values.dtype}")
    return values


def inpaint(
    mesh_or_surface: ImplicitSurface | trimesh.Trimesh | str | os.PathLike,
    values: ArrayLike | None = None,
    missing: ArrayLike | None = None,
    *,
    method: str = "harmonic",
    resolution: int = 128,
    tol: float = 1e-5,
    max_iterations: int | None = None,
    device: DeviceLike = None,
    progress: bool | None = None,
    return_info: bool = False,
) -> np.ndarray | tuple[np.ndarray, SurfaceInpaintInfo]:
    """Fill data missing over part of a surface by a PDE on the implicit surface.

    Parameters
    ----------
    mesh_or_surface : trimesh.Trimesh, str, PathLike or ImplicitSurface
        A closed mesh (or a file trimesh reads), whose implicit surface is built at
        `resolution`; or an ImplicitSurface with the data on its band.
    values : array_like, optional
        On a mesh: (vertices,) or (vertices, channels), by default the mesh's RGB vertex
        colours. On an ImplicitSurface: dense ((channels,) + shape) or band form.
    missing : array_like
        On a mesh: a boolean mask per vertex, or integer vertex indices. On an
        ImplicitSurface: a boolean array of values' spatial form (the cells whose closest
        point lies in the missing region).
    method : {'harmonic', 'transport'}, optional
        'harmonic': Laplace-Beltrami u = 0 in the hole, the known data as the boundary
        condition. 'transport': from that, the thesis' transport along isophotes with
        intrinsic curvature diffusion (chapter 3 written intrinsically; up to 200 cycles of
        17 steps: slower, keeps edges crossing the hole sharper).
    resolution : int, optional
        Grid cells across a mesh's longest side.
    tol : float, optional
        Stop once the error left (a step's largest change in the hole over the iteration's
        rate of convergence) is below tol times the known data's range.
    max_iterations : int, optional
        At most this many harmonic steps (default: twice Chebyshev's bound for tol).
    device : str or int or Runtime, optional
        The OpenCL device for a mesh's surface.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    return_info : bool, optional
        Also return a SurfaceInpaintInfo.

    Returns
    -------
    ndarray or (ndarray, SurfaceInpaintInfo)
        The values with the missing ones filled, in values' form and dtype (integers
        rounded and clipped to their range); the known values are returned unchanged.

    Raises
    ------
    InputError
        For masks or values of another shape, nothing known or a mesh without colours
        and no values.

    Examples
    --------
    >>> import numpy as np, trimesh
    >>> from clpde.surface import inpaint
    >>> ball = trimesh.creation.icosphere(3)
    >>> x, y, z = ball.vertices.T
    >>> u = x / (2 - z)  # smooth; the fill is the harmonic function with u's values on the rim
    >>> hole = z < -0.7
    >>> filled = inpaint(ball, u, hole, resolution=32)
    >>> filled.shape == u.shape, bool((filled[~hole] == u[~hole]).all())
    (True, True)
    """
    if missing is None:
        raise InputError("give missing: where the data is missing (a mask or vertex indices)")
    options = dict(method=method, tol=tol, max_iterations=max_iterations, progress=progress)
    if isinstance(mesh_or_surface, ImplicitSurface):
        surf = mesh_or_surface
        vals, hole, restore = _surface_form(surf, values, missing)
        out, info = fill_band(surf, vals, hole, **options)
        out = restore(out)
        return (out, info) if return_info else out
    mesh = load_mesh(mesh_or_surface)
    data = mesh_values(mesh, values)
    mask = vertex_mask(missing, len(mesh.vertices))
    if not np.all(np.isfinite(data[~mask])):
        raise InputError("values contain NaN or infinite entries at vertices not missing")
    with encloses_volume(mesh_or_surface):
        surf = ImplicitSurface.from_mesh(mesh, resolution=resolution, device=device)
    filled, info = fill_mesh(surf, data, mask, **options)
    return (filled, info) if return_info else filled


def fill_mesh(surf: ImplicitSurface, data: np.ndarray, mask: np.ndarray, **options):
    """Vertex data with the masked vertices filled on `surf` (made from the mesh)."""
    known_data = np.where(mask.reshape((-1,) + (1,) * (data.ndim - 1)), 0, data)
    band = surf.band_values(surf.field_from_mesh(known_data.astype(np.float64)))
    # a cell is in the hole when a missing vertex has a share in its value
    hole = surf.band_values(surf.field_from_mesh(mask.astype(np.float64))) > 0
    vals = band.reshape(-1, surf.ext_band.n)
    out, info = fill_band(surf, vals, hole, **options)
    filled = np.array(data, copy=True)
    if mask.any():
        sampled = surf.sample(out if data.ndim == 2 else out[0], surf.mesh.vertices[mask])
        if np.issubdtype(data.dtype, np.integer):
            limits = np.iinfo(data.dtype)
            sampled = np.clip(np.rint(sampled), limits.min, limits.max)
        filled[mask] = sampled.astype(filled.dtype)
    return filled, info


# ---- the command line's run: a mesh file, a mask file, pictures and the filled mesh --------
MISSING_COLOUR = (0.55, 0.55, 0.55)  # the hole in the "before" picture
