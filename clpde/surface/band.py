"""A surface's narrow band: its construction from psi (the band lists, closest points and
their interpolation stencils), the band form's conversions and checks, and the band's bricks
(Band). The surface (implicit.py) and the device state of the flows' data (storage.py) build
on this module; neither reaches into the other's members.
"""

from __future__ import annotations

import warnings

import numpy as np
import pyopencl.array as cla

from ..bricks import DEFAULT_BRICK, EXT, NODE, REACH, BrickBand, dilate_axes
from ..errors import InputError
from ..fields import compact

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/band.cl",)


# The closest-point interpolations, by name, and their codes in the kernels.
INTERPOLATIONS = {"tricubic": 3, "trilinear": 1}
# Interpolation nodes per axis.
_NODES = {3: 4, 1: 2}
# Farthest interpolation node from a point, in cells: the step band must contain them.
NODE_REACH = {3: 2 * np.sqrt(3.0), 1: np.sqrt(3.0)}


def interp_code(interpolation: str) -> int:
    """The kernels' code of an interpolation named in INTERPOLATIONS."""
    code = INTERPOLATIONS.get(interpolation)
    if code is None:
        raise InputError(
            f"interpolation must be one of {sorted(INTERPOLATIONS)}, not {interpolation!r}"
        )
    return code


def values_as_array(values, shape: tuple, dtype) -> np.ndarray:
    """What a field function returned, as an array of `dtype`: `shape` for an array result,
    (channels,) + `shape` for a sequence of them."""
    if isinstance(values, (list, tuple)):
        out = np.stack([np.broadcast_to(np.asarray(v, np.float64), shape) for v in values])
    else:
        out = np.broadcast_to(np.asarray(values, np.float64), shape)
    return np.array(out, dtype=dtype)


def _warn(message: str) -> None:
    warnings.warn(message, stacklevel=3)


# ---- the band's construction, once per psi (ImplicitSurface._set_psi) ----------------------
def narrow_bands(surf) -> None:
    """node_band, its runs, reach_band and reach_band's closest-point stencils."""
    g, q = surf.grid, surf.runtime.queue
    nodes = cla.zeros(q, g.padded_shape, np.uint8)
    g.launch_list(
        g.kernel("surface/band.cl", "band_mark_nodes"),
        surf.ext_band,
        surf.cp_base.data,
        nodes.data,
        *g.strides(),
        np.int32(_NODES[surf.interp]),
    )
    surf.node_band = compact(surf.runtime, nodes)
    surf.step_runs = g.runs(surf.node_band)
    reach = cla.zeros(q, g.padded_shape, np.uint8)
    g.launch_list(
        g.kernel("surface/band.cl", "band_mark_stencil"), surf.node_band, reach.data, *g.strides()
    )
    surf.reach_band = compact(surf.runtime, reach)
    surf.reach_stencils = cp_stencils(surf, surf.reach_band, closest_points(surf, surf.reach_band))


def closest_points(surf, band):
    """Closest points of a band's cells, padded index units, on the device."""
    g, q = surf.grid, surf.runtime.queue
    n = max(band.n, 1)
    cp = [cla.empty(q, n, g.dtype) for _ in range(3)]
    g.launch_list(
        g.kernel("surface/band.cl", "band_closest_points"),
        band,
        surf.psi_dev.data,
        g.scalar(1.0 / surf.spacing),
        cp[0].data,
        cp[1].data,
        cp[2].data,
        *g.strides(),
    )
    return cp


def cp_stencils(surf, band, cp):
    """Per band cell: the flat index of its closest point's first interpolation node and
    the point's offsets (3, n) from floor(cp), on the device (psi is fixed, so the
    re-extension after each step only gathers and weighs)."""
    g, q = surf.grid, surf.runtime.queue
    n = max(band.n, 1)
    base = cla.empty(q, n, np.int32)
    frac = cla.empty(q, (3, n), g.dtype)
    g.launch_list(
        g.kernel("surface/band.cl", "band_cp_stencils"),
        band,
        *(c.data for c in cp),
        *g.strides(),
        *g.padded_dims(),
        np.int32(surf.interp),
        base.data,
        frac.data,
    )
    return base, frac


def check_band_clear_of_border(surf) -> None:
    """Band cells must keep 2 cells from the volume's border, so that every stencil
    and interpolation node stays inside the padded buffer's meaningful values."""
    band = np.abs(surf.psi) < surf.outer * surf.spacing
    if not band.any():
        raise InputError("the band is empty: the spacing is too coarse for this surface")
    m = 2
    edge = np.ones_like(band)
    edge[m:-m, m:-m, m:-m] = False
    if np.any(band & edge):
        raise InputError(
            f"the band around the surface (|psi| < {surf.outer:.1f} cells) reaches within "
            f"{m} cells of the volume's border: pad psi by {int(np.ceil(surf.outer)) + m} "
            "cells a side (e.g. from_function with larger bounds)"
        )
    if surf.step_band.n == 0:
        raise InputError("the band is empty: the spacing is too coarse for this surface")
    # a medial axis (|grad psi| far from 1) inside the band means thin features are
    # resolved by too few cells: the flows still run but lose accuracy there
    # central differences at the band's cells only (a whole-volume gradient would take
    # three float64 volumes); band cells are 2 cells from the border, checked above
    cells = np.flatnonzero(band)
    p = surf.psi.reshape(-1)
    _, ny, nx = surf.shape
    diffs = [p[cells + s] - p[cells - s] for s in (1, nx, nx * ny)]
    slope = np.sqrt(sum(d**2 for d in diffs)) / (2 * surf.spacing)
    bad = float(np.mean(slope < 0.5))
    if bad > 0:
        _warn(
            f"the grid is too coarse for this shape's thinnest features: {100 * bad:.2f}% "
            "of the band lies on a medial axis (|grad psi| < 0.5); use a finer spacing "
            f"(below {surf.spacing / 2:g}) or a narrower band"
        )


class Band:
    """Data on one surface's band, for the surface and its flows: the band form's cells, the
    checks and conversions of data given densely or in band form, and the band's bricks
    (built once per psi and brick size). The surface makes a new one when psi changes."""

    def __init__(self, surf, brick: tuple[int, int, int] = DEFAULT_BRICK):
        self.surf = surf
        self.brick = tuple(brick)
        self._cells = None  # the band form's cells (band_indices), built when asked
        self._bricks = None  # built when a flow on bricks first needs them
        self._places = None  # the band form's places in the bricks (BrickFlow)

    def bricks(self):
        """(BrickBand, psi's tiles on it, {EXT, REACH: re-extension lists}) of the band in dense
        bricks (bricks.py), built once per psi.

        Stored: every brick holding a cell a brick kernel reads, the cells of the extension
        and reach bands with their psi neighbours (closest points) and the nodes with psi two
        cells away along each axis (the fluxes one cell back)."""
        s = self.surf
        brick = tuple(self.brick)
        if self._bricks is None or self._bricks[0].brick != brick:
            g = s.grid
            bits = np.zeros(g.padded_shape, np.uint8)
            flat = bits.reshape(-1)
            for band, bit in ((s.node_band, NODE), (s.reach_band, REACH), (s.ext_band, EXT)):
                flat[band.indices.get()[: band.n]] |= bit
            stored = dilate_axes(bits & NODE != 0, 2) | dilate_axes(bits & (REACH | EXT) != 0, 1)
            bb = BrickBand.build(s.runtime, g.padded_shape, stored, bits, brick)
            # psi in tiles of halo 2, what the heat step reads around each brick
            psi = bb.tiles(s.psi_dev, 2)
            q = s.runtime.queue

            def stencils(band, base, frac):
                # targets as brick-storage indices and first nodes as node codes, in the
                # order of the nodes, so consecutive entries gather from the same bricks
                # (faster than in the targets' order: docs/surface_storage.md)
                target = bb.index_of(band.indices.get()[: band.n])
                first = bb.node_code(base.get()[: band.n])
                order = np.argsort(first, kind="stable")
                first = first[order]
                offsets = np.ascontiguousarray(frac.get()[:, : band.n][:, order])
                return (
                    band.n,
                    cla.to_device(q, target[order]),
                    cla.to_device(q, first),
                    cla.to_device(q, offsets),
                )

            lists = {
                EXT: stencils(s.ext_band, s.cp_base, s.cp_frac),
                REACH: stencils(s.reach_band, *s.reach_stencils),
            }
            self._bricks = (bb, psi, lists)
        return self._bricks

    def cells(self) -> tuple[np.ndarray, np.ndarray]:
        """(flat indices into `shape`, flat padded indices) of the extension band's cells."""
        if self._cells is None:
            s = self.surf
            g = s.grid
            padded = s.ext_band.indices.get()[: s.ext_band.n].astype(np.int64)
            z, rest = np.divmod(padded, g.sxy)
            y, x = np.divmod(rest, g.sx)
            _, ny, nx = s.shape
            flat = ((z - g.ghost) * ny + (y - g.ghost)) * nx + (x - g.ghost)
            self._cells = (flat, padded)
        return self._cells

    def coordinates(self) -> np.ndarray:
        """World (x, y, z) of the extension band's cells, shape (n, 3), in band-form order."""
        s = self.surf
        flat = self.cells()[0]
        _, ny, nx = s.shape
        z, rest = np.divmod(flat, ny * nx)
        y, x = np.divmod(rest, nx)
        return s.origin + s.spacing * np.stack([x, y, z], axis=1).astype(np.float64)

    def closest_points(self) -> np.ndarray:
        """World closest points of the extension band's cells, shape (n, 3), from central
        differences of psi at the band's cells only."""
        s = self.surf
        flat = self.cells()[0]
        p = s.psi.reshape(-1)
        _, ny, nx = s.shape
        grad = [(p[flat + d] - p[flat - d]) / (2 * s.spacing) for d in (1, nx, nx * ny)]
        norm = np.sqrt(grad[0] ** 2 + grad[1] ** 2 + grad[2] ** 2)
        norm[norm == 0] = 1.0
        d = p[flat] / norm
        return self.coordinates() - d[:, None] * np.stack(grad, axis=1)

    def values(self, u: np.ndarray) -> np.ndarray:
        """Dense data (the grid's shape, or (channels,) + it) in band form, dtype kept."""
        shape = self.surf.shape
        if u.shape == shape:
            return u.reshape(-1)[self.cells()[0]]
        if u.ndim == 4 and u.shape[1:] == shape:
            return u.reshape(u.shape[0], -1)[:, self.cells()[0]]
        raise InputError(
            f"u must have the surface's grid shape {shape} (or (channels,) + that), got {u.shape}"
        )

    def dense(self, v: np.ndarray, fill: float) -> np.ndarray:
        """Band-form values as a dense volume, `fill` off the band, float dtype kept."""
        nc = self.form_channels(v)
        n = self.surf.ext_band.n
        if nc is None:
            raise InputError(
                f"values must have shape ({n},) or (channels, {n}) (the band form), got {v.shape}"
            )
        shape = self.surf.shape
        dtype = v.dtype if np.issubdtype(v.dtype, np.floating) else np.float64
        out = np.full((nc, int(np.prod(shape))), fill, dtype)
        out[:, self.cells()[0]] = v.reshape(nc, -1)
        out = out.reshape((nc,) + shape)
        return out[0] if v.ndim == 1 else out

    def form_channels(self, u: np.ndarray) -> int | None:
        """Channels of band-form data (shape (n,) or (channels, n)), None for other shapes."""
        n = self.surf.ext_band.n
        if u.ndim == 1 and u.shape[0] == n:
            return 1
        if u.ndim == 2 and u.shape[1] == n:
            return u.shape[0]
        return None

    def checked_values(self, u: np.ndarray) -> np.ndarray:
        """Band-form data as (channels, n), checked as `as_channels` checks."""
        if not np.issubdtype(u.dtype, np.number) or np.iscomplexobj(u):
            raise InputError(f"u must hold real numbers, not {u.dtype}")
        values = u.reshape(self.form_channels(u), -1)
        if not np.all(np.isfinite(values)):
            raise InputError("u contains NaN or infinite values in the band around the surface")
        return values

    def padded_from(self, u: np.ndarray) -> np.ndarray:
        """Band-form data as a padded (channels, PZ, PY, PX) host volume in the grid's dtype,
        zeros off the band (no flow reads them), checked as `as_channels` checks."""
        values = self.checked_values(u)
        g = self.surf.grid
        padded = np.zeros((values.shape[0], g.volume), g.dtype)
        padded[:, self.cells()[1]] = values
        return padded.reshape((values.shape[0],) + g.padded_shape)

    def as_channels(self, u, what="u"):
        """(nc, nz, ny, nx) float64 copy of scalar or channel-first vector data."""
        u = np.asarray(u)
        if u.shape == self.surf.shape:
            data = u[None]
        elif u.ndim == 4 and u.shape[1:] == self.surf.shape:
            data = u
        else:
            raise InputError(
                f"{what} must have the surface's grid shape {self.surf.shape} (or (channels,) + "
                f"that "
                f"for vector data), got {u.shape}; flows also take the band form, shape "
                f"({self.surf.ext_band.n},) or (channels, {self.surf.ext_band.n}) (band_values)"
            )
        if not np.issubdtype(u.dtype, np.number) or np.iscomplexobj(u):
            raise InputError(f"{what} must hold real numbers, not {u.dtype}")
        data = data.astype(np.float64)
        band = np.abs(self.surf.psi) < self.surf.outer * self.surf.spacing
        if not np.all(np.isfinite(data[:, band])):
            raise InputError(
                f"{what} contains NaN or infinite values in the band around the surface"
            )
        return data

    def places(self, bricks) -> np.ndarray:
        """The band form's cells as places in `bricks`' storage."""
        if self._places is None or self._places[0] is not bricks:
            self._places = (bricks, bricks.index_of(self.cells()[1]))
        return self._places[1]


def extend_defines(interp: int, nc: int, normalize: bool = False, line_field: bool = False) -> dict:
    """The defines of surface/extend.cl's program: every lookup in that file passes all of
    them (the ones a kernel ignores at their defaults), so a flow's re-extension, sampling
    and the extension PDE share one build."""
    return {"INTERP": interp, "NC": nc, "NORMALIZE": int(normalize), "LINE_FIELD": int(line_field)}
