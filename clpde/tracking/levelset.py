"""2D level-set machinery on the device: signed distance start, narrow band, reinitialisation.

A `LevelSet` holds u on a ghost-padded grid (ghost width 2 for the slope-limited upwind
stencils of kernels/tracking/levelset.cl), a band of the cells with |u| < w built on the
device in the storage `storage` names (storage.py: a compacted list of the cells, or the
bricks that hold them), and a PDE reinitialisation with Russo and Smereka's subcell fix
that keeps the zero level set in place. The morphing flow of clpde.track steps u inside the
band; other level-set flows can do the same.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from ..errors import InputError
from ..fields import Field, Grid, PingPong
from .storage import STORAGES

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/levelset.cl",)

GHOST = 2
MARGIN = 2  # frozen cells around the caller's grid (see LevelSet)
REACH = 3  # a rebuild reinitialises the band dilated by this many cells (<= MARGIN + GHOST - 1)
CFL = 0.5  # largest distance in pixels a level set moves in one step
# Rebuild when the front comes this close to the band's outer ring. Between two checks
# (check_every steps) the front moves at most check_every * CFL pixels, so it cannot leave
# the band unnoticed while NEAR_EDGE >= check_every * CFL.
NEAR_EDGE = 1.0
REINIT_DT = 0.5  # Godunov reinitialisation is stable for dt <= 1/sqrt(2) in 2D; keep margin


def signed_distance(mask) -> np.ndarray:
    """Signed Euclidean distance to a mask's boundary: negative inside, positive outside.

    The boundary lies halfway between a pixel of the mask and its outside neighbour, so
    `signed_distance(mask) < 0` gives the mask back exactly.
    """
    from scipy import ndimage

    mask = np.asarray(mask, bool)
    if mask.ndim != 2:
        raise InputError(f"the mask must be 2-D, got shape {mask.shape}")
    if not mask.any():
        raise InputError("the mask is empty: mark at least one pixel of the object to follow")
    if mask.all():
        raise InputError(
            "the mask covers the whole image, so it has no boundary to follow; "
            "leave the background unmarked"
        )
    # the inside distances over the mask's box grown by 1 px only: a pixel of the mask is
    # no nearer to an outside pixel beyond the box than to the box's rim, outside too (the
    # same values as over the whole frame, at the object's cost)
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    box = (
        slice(max(rows[0] - 1, 0), rows[-1] + 2),
        slice(max(cols[0] - 1, 0), cols[-1] + 2),
    )
    inside = np.zeros(mask.shape)
    inside[box] = ndimage.distance_transform_edt(mask[box])
    outside = ndimage.distance_transform_edt(~mask)
    return np.where(mask, 0.5 - inside, outside - 0.5)


class LevelSet:
    """A 2D level set u on the device with its narrow band.

    The grid is the caller's (ny, nx) grid with a frozen margin of MARGIN cells added on
    every side, holding edge-replicated values (`pad` does the same for data fields on this
    grid). Band and reinitialisation kernels update only the cells inside the margin, so
    their stencils never reach the ghosts and no ghost refresh is needed between steps:
    each step is a single kernel launch.

    band_width w: the band holds the cells with |u| < w; its outer ring (w - 1 <= |u| < w)
    is the edge a flow watches to ask for a rebuild.
    """

    def __init__(
        self,
        runtime,
        u0,
        band_width: float = 3.0,
        dtype=np.float32,
        storage: str = "lists",
        group_per_brick: bool | None = None,
    ):
        layout = STORAGES[storage]  # a name TrackOptions checked (StorageTable.choose)
        u0 = np.asarray(u0, np.float64)
        if u0.ndim != 2:
            raise InputError(f"the level set must be 2-D, got shape {u0.shape}")
        if band_width < 2:
            raise InputError(f"band_width must be at least 2 pixels, not {band_width}")
        self.shape = u0.shape
        ny, nx = u0.shape
        self.runtime = runtime
        self.grid = Grid(runtime, nx + 2 * MARGIN, ny + 2 * MARGIN, 1, GHOST, np.dtype(dtype))
        self.band_width = float(band_width)
        # GPUs take a brick per work-group; forced either way only to test both on a CPU.
        group = not runtime.is_cpu if group_per_brick is None else bool(group_per_brick)
        self.storage, self.store = storage, layout(self.grid, MARGIN, group)
        self.u = PingPong(Field.from_host(self.grid, self.pad(u0)[np.newaxis]))
        self._phi0 = Field.empty(self.grid)
        inner = np.zeros(self.grid.padded_shape[1:], np.uint8)
        self.grid.interior(inner)[MARGIN:-MARGIN, MARGIN:-MARGIN] = 1
        self.active = self.store.cells(cla.to_device(runtime.queue, inner))
        # Ghost entries stay 0 (levelset_mark_band writes the interior only).
        self.band_mask = cla.zeros(runtime.queue, self.grid.padded_shape[1:], np.uint8)
        self._near_mask = cla.zeros(runtime.queue, self.grid.padded_shape[1:], np.uint8)
        self._near_rows = cla.zeros(runtime.queue, self.grid.padded_shape[1:], np.uint8)
        self.band = None
        self.rebuilds = 0
        self.build_band()

    @staticmethod
    def pad(values: np.ndarray) -> np.ndarray:
        """(ny, nx) data, or (C, ny, nx) channels, to the level set's grid: the frozen margin
        replicates the edge."""
        values = np.asarray(values, np.float64)
        return np.pad(values, ((0, 0),) * (values.ndim - 2) + ((MARGIN, MARGIN),) * 2, mode="edge")

    def assign(self, u) -> None:
        """Replace u by new (ny, nx) values (a signed distance, e.g. a shifted one) in the
        same device buffers, and rebuild the band around its zero set."""
        u = np.asarray(u, np.float64)
        if u.shape != self.shape:
            raise InputError(f"the level set must have shape {self.shape}, got {u.shape}")
        padded = np.zeros(self.grid.padded_shape, self.grid.dtype)
        self.grid.interior(padded)[0] = self.pad(u)
        self.u.cur.data.set(padded)
        self.u.cur.fill_ghosts()
        self.build_band()

    # ---- band --------------------------------------------------------------------------
    def build_band(self) -> None:
        """Mark |u| < w on the device and compact it into the band's index list."""
        g = self.grid
        g.launch(
            g.kernel("tracking/levelset.cl", "levelset_mark_band"),
            self.u.cur.data.data,
            self.band_mask.data,
            g.scalar(self.band_width),
            np.int32(MARGIN),
        )
        self.band = self.store.cells(self.band_mask)
        # Cells outside the band are never written by band kernels: make both buffers agree
        # there so swapping never brings back stale values.
        self.u.nxt.assign(self.u.cur)

    def rebuild(self, iterations: int | None = None) -> None:
        """Reinitialise u near the front, then rebuild the band around its zero set.

        The region reinitialised is the current band dilated by REACH cells. The front is
        still inside the band when a rebuild is asked for, so this region holds every cell
        within REACH of the front: those the new band can take in. Cells farther out keep
        older values, correct in sign and no closer to the front than they really are, and
        are corrected at a later rebuild before the band reaches them.
        """
        self.dilate_band()
        self.reinitialize(iterations, cells=self.store.cells(self._near_mask))
        self.build_band()
        self.rebuilds += 1

    def dilate_band(self) -> None:
        """Mark the movable cells within REACH cells of the band (into _near_mask)."""
        g = self.grid
        g.launch(
            g.kernel("tracking/levelset.cl", "levelset_dilate_band_rows"),
            self.band_mask.data,
            self._near_rows.data,
            np.int32(REACH),
        )
        g.launch(
            g.kernel("tracking/levelset.cl", "levelset_dilate_band_cols"),
            self._near_rows.data,
            self._near_mask.data,
            np.int32(REACH),
            np.int32(MARGIN),
        )

    # ---- reinitialisation --------------------------------------------------------------
    def reinitialize(
        self,
        iterations: int | None = None,
        dt: float = REINIT_DT,
        cells=None,
        subcell_fix: bool = True,
    ) -> None:
        """PDE reinitialisation with the Russo-Smereka subcell fix at the front, of the
        given cells (an IndexList; default: every cell inside the frozen margin).

        Information travels one cell per 1/dt iterations, so the default count corrects u
        out to the band's width plus two cells beyond the front. subcell_fix=False runs the
        plain Godunov scheme everywhere (it moves the front; for comparisons).
        """
        if iterations is None:
            iterations = int(np.ceil((self.band_width + 2) / dt))
        cells = self.active if cells is None else cells
        plain = {} if subcell_fix else {"PLAIN_REINIT": 1}
        kernel = self.band_kernel("tracking/levelset.cl", self.store.KERNELS["reinit"], **plain)
        tail = self.store.reinit_args(cells, dt)
        self._phi0.assign(self.u.cur)
        self.u.nxt.assign(self.u.cur)  # cells left out are the same in both buffers
        for _ in range(iterations):
            args = (self.u.cur.data.data, self._phi0.data.data, self.u.nxt.data.data)
            self.launch_band(kernel, cells, *args, *tail)
            self.u.swap()

    # ---- the band's storage (self.store: storage.py) ---------------------------------------
    def band_kernel(self, filename: str, name: str, **defines):
        """A kernel of the band's storage: list kernels as they are, brick kernels built for
        this brick size and launch geometry."""
        return self.store.kernel(filename, name, **defines)

    def band_parts(self, cells=None) -> int:
        """How many work-items a band launch over `cells` (default: the band) has: the
        length of its per-work-item statistics."""
        return self.store.parts(self.band if cells is None else cells)

    def launch_band(self, kernel, cells, *args):
        """Run a band kernel (band_kernel's) over `cells` (the band, or a BrickSet / IndexList
        of this storage)."""
        if cells.n == 0:
            return None
        return self.store.launch(kernel, cells, *args)

    def stored_cells(self) -> int:
        """Cells the band's launches visit: the band's cells, or its bricks' cells."""
        return self.store.stored(self.band)

    # ---- results -----------------------------------------------------------------------
    def crop(self, padded: np.ndarray) -> np.ndarray:
        return padded[..., MARGIN:-MARGIN, MARGIN:-MARGIN]

    def values(self) -> np.ndarray:
        """u on the caller's (ny, nx) grid, float64."""
        return self.crop(self.u.cur.to_host()[0]).astype(np.float64)

    def inside(self) -> np.ndarray:
        """The region u < 0 as a boolean (ny, nx) mask."""
        return self.values() < 0

    def band_cells(self) -> np.ndarray:
        """The band as a boolean (ny, nx) mask (for inspection and tests)."""
        g = self.grid
        return self.crop(g.interior(self.band_mask.get()[np.newaxis])[0]) > 0
