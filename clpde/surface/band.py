"""Data on a surface's narrow band, in either storage (band lists or bricks): the band form's
conversions and checks (Band), and the device state of a flow's data (BandFlow on the lists,
BrickFlow on the bricks). Both implicit.py and flows.py build on this module; neither reaches
into the other's members.
"""

from __future__ import annotations

import warnings

import numpy as np
import pyopencl.array as cla

from ..bricks import DEFAULT_BRICK, EXT, NODE, REACH, BrickBand, dilate_axes
from ..errors import InputError
from ..fields import compact

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = (
    "surface/band.cl",
    "surface/bricks.cl",
    "surface/extend.cl",
    "surface/flows.cl",
    "surface/heat.cl",
)


# Interpolation nodes per axis.
_NODES = {3: 4, 1: 2}


def _warn(message: str) -> None:
    warnings.warn(message, stacklevel=3)


# ---- the band's construction, once per psi (ImplicitSurface._set_psi) ----------------------
def narrow_bands(surf) -> None:
    """node_band, its runs, reach_band and reach_band's closest-point stencils."""
    g, q = surf.grid, surf.runtime.queue
    nodes = cla.zeros(q, g.padded_shape, np.uint8)
    g.launch_list(
        g.kernel("surface/band.cl", "mark_nodes"),
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
        g.kernel("surface/band.cl", "mark_stencil"), surf.node_band, reach.data, *g.strides()
    )
    surf.reach_band = compact(surf.runtime, reach)
    surf.reach_stencils = cp_stencils(surf, surf.reach_band, closest_points(surf, surf.reach_band))


def closest_points(surf, band):
    """Closest points of a band's cells, padded index units, on the device."""
    g, q = surf.grid, surf.runtime.queue
    n = max(band.n, 1)
    cp = [cla.empty(q, n, g.dtype) for _ in range(3)]
    g.launch_list(
        g.kernel("surface/band.cl", "closest_points"),
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
        g.kernel("surface/band.cl", "cp_stencils"),
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
                # (10-20% faster than in the targets' order, 128^3 and 217^3)
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


def _offsets(grid, sides: int):
    """Signed one-sided difference offsets (ex, ey, ez) for a choice of sides (bits x, y, z)."""
    sx, sxy = int(grid.sx), int(grid.sxy)
    return tuple(np.int32(-s if (sides >> a) & 1 else s) for a, s in enumerate((1, sx, sxy)))


def extend_defines(interp: int, nc: int, normalize: bool = False, line_field: bool = False) -> dict:
    """The defines of surface/extend.cl's program: every lookup in that file passes all of
    them (the ones a kernel ignores at their defaults), so a flow's re-extension, sampling
    and the extension PDE share one build."""
    return {"INTERP": interp, "NC": nc, "NORMALIZE": int(normalize), "LINE_FIELD": int(line_field)}


# Each flow's step kernel (file, name) in each band storage.
STEP_KERNELS = {
    "heat": {
        "lists": ("surface/heat.cl", "heat_step"),
        "bricks": ("surface/bricks.cl", "brick_heat_step"),
    },
    "flow": {
        "lists": ("surface/flows.cl", "flow_step"),
        "bricks": ("surface/bricks.cl", "brick_flow_step"),
    },
    "turk": {
        "lists": ("surface/heat.cl", "turk_step"),
        "bricks": ("surface/bricks.cl", "brick_turk_step"),
    },
}


class BandFlow:
    """Device state of data on a surface's band lists: `cur` (extended) and a scratch volume
    `tmp`, dense volumes; a step runs over the node band's runs, cur -> tmp."""

    storage = "lists"

    def __init__(
        self,
        surf,
        u,
        normalize: bool = False,
        extend: bool = True,
        line_field: bool = False,
        defines: dict | None = None,
    ):
        self.surf = surf
        self.input = np.asarray(u)
        # band form (values at the band's cells only): no dense float64 copy on the way
        self.band_form = surf.band.form_channels(self.input) is not None
        g = surf.grid
        if self.band_form:
            padded = surf.band.padded_from(self.input)
            surf.runtime.check_alloc(padded.nbytes, "surface volume")
            self.cur = cla.to_device(surf.runtime.queue, padded)
            del padded
        else:
            self.cur = g.upload(surf.band.as_channels(u))
        self.nc = self.cur.shape[0]
        # the step kernels' defines, with the channel count
        self.defines = {"NC": self.nc, **(defines or {})}
        self.psi = surf.psi_dev
        self.normalize = normalize
        self.tmp = self.cur.copy()
        self._extend_kernel = g.kernel(
            "surface/extend.cl",
            "extend_cp",
            **extend_defines(surf.interp, self.nc, normalize, line_field),
        )
        self._stepped = False
        if extend:
            self.extend()

    def kernel(self, filename: str, name: str, **defines):
        """Kernel `name` of `filename` with the flow's defines."""
        return self.surf.grid.kernel(filename, name, **{**self.defines, **defines})

    def step_kernel(self, flow: str):
        """The step kernel of `flow` (heat, flow, turk: STEP_KERNELS) in this storage."""
        filename, name = STEP_KERNELS[flow][self.storage]
        return self.kernel(filename, name)

    def step(self, kernel, sides: int, *args, channels: int = 1) -> None:
        """One step cur -> tmp over the node band's runs: kernel(cur, tmp, psi, *args, the
        one-sided offsets of `sides`, the strides, the runs); then after_step."""
        g = self.surf.grid
        g.launch_runs(
            kernel,
            self.surf.step_runs,
            self.cur.data,
            self.tmp.data,
            self.psi.data,
            *args,
            *_offsets(g, sides),
            *g.strides(),
            channels=channels,
        )
        self.after_step()

    def fixed(self, values: np.ndarray, halo: int = 0) -> cla.Array:
        """A fixed field (channels, nz, ny, nx) on the device in this storage (a dense
        volume; halo: what the bricks store around each brick)."""
        return self.surf.grid.upload(values)

    def extend(self) -> None:
        """Re-extend cur along the normals over the whole band (through tmp; cur holds the
        result)."""
        s = self.surf
        self._extend(self.cur, self.tmp, s.ext_band, s.cp_base, s.cp_frac)
        self.cur, self.tmp = self.tmp, self.cur
        self._stepped = False

    def _extend(self, src, dst, band, base, frac) -> None:
        g = self.surf.grid
        g.launch_list(
            self._extend_kernel,
            band,
            src.data,
            dst.data,
            base.data,
            frac.data,
            *g.strides(),
            channels=1,
        )

    def after_step(self) -> None:
        """The step wrote tmp over the node band: extend it back into cur over the cells the
        next step reads (surf.reach_band)."""
        s = self.surf
        self._extend(self.tmp, self.cur, s.reach_band, *s.reach_stencils)
        self._stepped = True

    # ---- TV's dynamic lambda: per-cell terms of its surface integrals ----
    @property
    def terms_size(self) -> int:
        """Entries of each array of lambda terms (one per node)."""
        return self.surf.node_band.n

    def lambda_terms(self, u0, terms, sides: int, eps: float) -> None:
        """Enqueue the terms of (C.2) at every node (surface/flows.cl's tv_lambda_terms)."""
        s = self.surf
        g = s.grid
        g.launch_list(
            self.kernel("surface/flows.cl", "tv_lambda_terms"),
            s.node_band,
            self.cur.data,
            u0.data,
            self.psi.data,
            *_lambda_scalars(s, eps),
            *_offsets(g, sides),
            *g.strides(),
            *(a.data for a in terms),
        )

    def result(self) -> np.ndarray:
        if self._stepped:
            # tmp still holds the last step at every node: extend the whole band from it
            s = self.surf
            self._extend(self.tmp, self.cur, s.ext_band, s.cp_base, s.cp_frac)
            self._stepped = False
        dtype = _result_dtype(self.input)
        if self.band_form:
            values = self.cur.get().reshape(self.nc, -1)[:, self.surf.band.cells()[1]]
            return (values[0] if self.input.ndim == 1 else values).astype(dtype)
        out = self.surf.grid.download(self.cur)
        out = out[0] if self.input.shape == self.surf.shape else out
        return out.astype(dtype)


class BrickFlow:
    """BandFlow's state on the surface's bricks (bricks.py): `cur` (extended) and `tmp`,
    brick buffers; a flow steps cur -> tmp on the bricks holding nodes, then re-extends
    tmp -> cur over the reach band (after_step), the whole band when it returns. The step
    kernels and the re-extension come from one build of bricks.cl (`kernel`)."""

    storage = "bricks"
    step_kernel = BandFlow.step_kernel

    def __init__(
        self,
        surf,
        u,
        normalize: bool = False,
        line_field: bool = False,
        defines: dict | None = None,
    ):
        self.surf = surf
        self.input = np.asarray(u)
        self.band_form = surf.band.form_channels(self.input) is not None
        g = surf.grid
        self.bricks, self.psi, self.lists = surf.band.bricks()
        b = self.bricks
        if self.band_form:
            values = surf.band.checked_values(self.input)
            self.nc = values.shape[0]
        else:
            # cells off the band come back as they went in, through the device's precision
            self.padded = g.pad(surf.band.as_channels(u)).astype(g.dtype)
            self.nc = self.padded.shape[0]
        _check_local_tiles(surf.runtime, b, max(self.nc, 2), g.dtype)
        if self.band_form:
            # straight into the bricks' places of the band's cells: no dense volume
            host = np.zeros((self.nc, b.plane), g.dtype)
            host[:, self._band_places()] = values
            b.runtime.check_alloc(host.nbytes, "brick volume")
            self.cur = cla.to_device(surf.runtime.queue, host)
            del host
        else:
            self.cur = b.scatter(self.padded, g.dtype)
        self.defines = {
            **extend_defines(surf.interp, self.nc, normalize, line_field),
            **(defines or {}),
        }
        # the stepped values, in the layout the re-extension reads (bricks with an apron)
        self.tmp = cla.zeros(surf.runtime.queue, (self.nc, b.apron_plane), g.dtype)
        b.launch(
            self.kernel("surface/bricks.cl", "brick_to_apron"),
            self.cur.data,
            self.tmp.data,
            channels=self.nc,
        )
        self.src_plane = np.int32(b.apron_plane)
        self._extend_kernel = self.kernel("surface/bricks.cl", "brick_extend_cp")
        self._extend(self.tmp, self.cur, EXT)
        self._stepped = False

    def kernel(self, filename: str, name: str, **defines):
        """Kernel `name` of `filename` with the brick layout's and the flow's defines."""
        s = self.surf
        return s.runtime.kernel(
            filename,
            name,
            s.grid.dtype,
            **self.bricks.defines(),
            GROUP_PER_BRICK=int(not s.runtime.is_cpu),
            **{**self.defines, **defines},
        )

    def step(self, kernel, sides: int, *args, channels: int = 1) -> None:
        """One step cur -> tmp on the bricks holding nodes: kernel(cur, tmp, psi tiles, *args,
        the one-sided directions of `sides`, the node rows, the brick tables); then
        after_step."""
        b = self.bricks
        b.launch(
            kernel,
            self.cur.data,
            self.tmp.data,
            self.psi.data,
            *args,
            *_signs(sides),
            b.node_rows.data,
            channels=channels,
        )
        self.after_step()

    def fixed(self, values: np.ndarray, halo: int = 0) -> cla.Array:
        """A fixed field (channels, nz, ny, nx) on the bricks: the plain layout, or (halo > 0)
        tiles with the cells within `halo` of each brick's faces, what a step reads around
        a cell (psi's layout)."""
        g = self.surf.grid
        padded = g.pad(np.asarray(values, np.float64))
        if halo:
            return self.bricks.scatter_tiles(padded, g.dtype, halo)
        return self.bricks.scatter(padded, g.dtype)

    def _band_places(self) -> np.ndarray:
        """The brick-storage places (plain layout) of the band form's cells, once per psi."""
        s = self.surf
        return s.band.places(self.bricks)

    def _extend(self, src, dst, which: int) -> None:
        n, target, base, frac = self.lists[which]
        b = self.bricks
        b.launch_list(
            self._extend_kernel,
            n,
            src.data,
            dst.data,
            base.data,
            frac.data,
            self.src_plane,
            target.data,
        )

    def after_step(self) -> None:
        self._extend(self.tmp, self.cur, REACH)
        self._stepped = True

    @property
    def terms_size(self) -> int:
        """Entries of each array of lambda terms (one per stored cell, zero off the nodes)."""
        return self.bricks.plane

    def lambda_terms(self, u0, terms, sides: int, eps: float) -> None:
        """Enqueue the terms of (C.2) at every node (bricks.cl's brick_lambda_terms)."""
        b = self.bricks
        b.launch(
            self.kernel("surface/bricks.cl", "brick_lambda_terms"),
            self.cur.data,
            u0.data,
            self.psi.data,
            *_lambda_scalars(self.surf, eps),
            *_signs(sides),
            b.cell_bits.data,
            *(a.data for a in terms),
        )

    def result(self) -> np.ndarray:
        if self._stepped:
            self._extend(self.tmp, self.cur, EXT)
            self._stepped = False
        g = self.surf.grid
        dtype = _result_dtype(self.input)
        if self.band_form:
            values = self.cur.get().reshape(self.nc, -1)[:, self._band_places()]
            return (values[0] if self.input.ndim == 1 else values).astype(dtype)
        out = g.interior(self.bricks.gather(self.cur, self.padded.copy(), EXT))
        out = out[0] if self.input.shape == self.surf.shape else out
        return out.astype(dtype)


def _check_local_tiles(runtime, bricks, channels: int, dtype) -> None:
    """On GPUs a brick's work-group holds a tile of halo 1 per channel in local memory: say
    when the data has more channels than the device's local memory holds."""
    if runtime.is_cpu:
        return
    bx, by, bz = bricks.brick
    need = channels * (bx + 2) * (by + 2) * (bz + 2) * np.dtype(dtype).itemsize
    have = runtime.device.local_mem_size
    if need > have:
        raise InputError(
            f"{channels} channels need {need} bytes of local memory a brick on "
            f"this device, which has {have}; use storage='lists' for this data, "
            "or fewer channels per call"
        )


def _result_dtype(data: np.ndarray):
    return data.dtype if np.issubdtype(data.dtype, np.floating) else np.float64


def _lambda_scalars(surf, eps: float):
    """inv_h, the smeared delta's half-width (cells) and e2 of the lambda terms' kernels."""
    g = surf.grid
    return g.scalar(1 / surf.spacing), g.scalar(1.5), g.scalar((surf.spacing * eps) ** 2)


def _signs(sides: int):
    """One-sided directions (+1 forward gradient, -1 backward) along x, y, z for a choice
    of sides (bits x, y, z), as the brick kernels take them."""
    return tuple(np.int32(-1 if (sides >> a) & 1 else 1) for a in range(3))


# storage name -> the device state of a flow's data in it (ImplicitSurface.storage)
FLOW_STATES = {"lists": BandFlow, "bricks": BrickFlow}


def make_flow(
    surf, u, normalize: bool = False, line_field: bool = False, defines: dict | None = None
):
    """The device state of data u on `surf` in the surface's band storage (surf.storage):
    a BandFlow on the band lists, a BrickFlow on the bricks. Both step with `step`, take
    their fixed fields from `fixed` and give the result back the same way; `defines` are the
    step kernels' (kernels/surface/flux.h)."""
    return FLOW_STATES[surf.storage](
        surf, u, normalize=normalize, line_field=line_field, defines=defines
    )
