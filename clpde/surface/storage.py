"""The device state of a flow's data on a surface's band, in either storage: BandFlow on the
band lists (dense volumes stepped over the node band's runs), BrickFlow on the band's bricks
(bricks.py). Both step, take their fixed fields and give their result back the same way, so
the flows (flows.py and the modules beside it) run in either through `make_flow`.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from ..bricks import EXT, REACH, StorageTable
from ..errors import DeviceLimitError, InputError
from .band import extend_defines

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = (
    "surface/bricks.cl",
    "surface/extend.cl",
    "surface/flows.cl",
    "surface/heat.cl",
)


def _offsets(grid, sides: int):
    """Signed one-sided difference offsets (ex, ey, ez) for a choice of sides (bits x, y, z)."""
    sx, sxy = int(grid.sx), int(grid.sxy)
    return tuple(np.int32(-s if (sides >> a) & 1 else s) for a, s in enumerate((1, sx, sxy)))


# Each flow's step kernel (file, name) in each band storage.
STEP_KERNELS = {
    "heat": {
        "lists": ("surface/heat.cl", "heat_step"),
        "bricks": ("surface/bricks.cl", "bricks_heat_step"),
    },
    "flow": {
        "lists": ("surface/flows.cl", "flows_step"),
        "bricks": ("surface/bricks.cl", "bricks_flow_step"),
    },
    "turk": {
        "lists": ("surface/heat.cl", "heat_turk_step"),
        "bricks": ("surface/bricks.cl", "bricks_turk_step"),
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
        """Enqueue the terms of (C.2) at every node (surface/flows.cl's flows_tv_lambda_terms)."""
        s = self.surf
        g = s.grid
        g.launch_list(
            self.kernel("surface/flows.cl", "flows_tv_lambda_terms"),
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
            self.kernel("surface/bricks.cl", "bricks_to_apron"),
            self.cur.data,
            self.tmp.data,
            channels=self.nc,
        )
        self.src_plane = np.int32(b.apron_plane)
        self._extend_kernel = self.kernel("surface/bricks.cl", "bricks_extend_cp")
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
        """Enqueue the terms of (C.2) at every node (bricks.cl's bricks_lambda_terms)."""
        b = self.bricks
        b.launch(
            self.kernel("surface/bricks.cl", "bricks_lambda_terms"),
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
    if bx * by * bz > runtime.device.max_work_group_size:  # a work-item a cell of the brick
        raise DeviceLimitError(
            f"bricks of {bx}x{by}x{bz} cells run in work-groups of {bx * by * bz} items, but "
            f"{runtime.device.name.strip()} allows at most {runtime.device.max_work_group_size}; "
            "use storage='lists'"
        )
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


# storage name -> the device state of a flow's data in it (ImplicitSurface.storage, checked
# by FLOW_STATES.choose)
FLOW_STATES = StorageTable(lists=BandFlow, bricks=BrickFlow)


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
