"""Region tracking on the narrow band in dense bricks, kept up on the device.

`region_tracker(..., storage="bricks")` builds a BrickRegionTracker: the same scheme as the
lists' tracker (regions.py, kernels/regions/regions.cl), with every level set (Phi and the
Phi-hats) stored as the bricks of clpde.bricks.BrickBand that the band needs, one
buffer per quantity (channels, nbricks + 2, BV), so memory follows the band, not the
volume. The kernels (kernels/regions/bricks.cl) run regions.h's, godunov.h's, reinit.h's
and extend.h's functions on a brick's tile, one work-item walking whole bricks.

Upkeep, after each reinitialisation (as OpenVDB's LevelSetTracker does, at brick
granularity): one kernel writes a flag word per brick (which of its 27 neighbours hold
cells within reach of its band cells, and its sign); the host reads only those nbricks
words and stores exactly the flagged bricks: it adds the missing ones and drops the
unflagged ones, rebuilding the Morton order and the neighbour table from brick
coordinates alone. A kernel copies the kept bricks into the new storage and fills the new
ones from the facing side of the brick that flagged them (Phi's sign, a magnitude beyond
the band: the reinitialisations that follow fix the cells they reach). The band masks are
then computed on the device per brick.

Dense numpy arrays stay the contract: `volumes()` gathers the bricks into dense volumes,
with the places of bricks not stored at FAR cells of their sign (known from the flags when
a brick was dropped, from the start otherwise).
"""

from __future__ import annotations

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from numpy.typing import ArrayLike

from ..bricks import DEFAULT_BRICK, BrickBand
from ..errors import InputError
from .tracker import (
    EXTEND_DT,
    EXTEND_FROM,
    EXTEND_ITERATIONS,
    REINIT_DT,
    RegionTracker,
)

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("regions/bricks.cl",)
BIT_STEP, BIT_REINIT = 1, 2
SIGN_BIT = 27  # of the upkeep's flag word: the brick's middle cell is inside (Phi < 0)
# The 27 neighbour offsets (x, y, z) in the neighbour table's order (x fastest).
_D = np.arange(-1, 2)
OFFSETS = np.stack([a.ravel() for a in np.meshgrid(_D, _D, _D, indexing="ij")[::-1]], 1)


class BrickRegionTracker(RegionTracker):
    """RegionTracker with the level sets in dense bricks of the band (see the module's
    docstring); brick=(BX, BY, BZ) its compile-time size, each side at least reinit_ring +
    2 cells (the upkeep looks one brick away)."""

    brick = DEFAULT_BRICK

    def __init__(self, *args, brick: tuple[int, int, int] = DEFAULT_BRICK, **kwargs):
        self.brick = tuple(int(b) for b in brick)
        super().__init__(*args, **kwargs)

    # ---- storage ----------------------------------------------------------------------------
    def _setup(self, cells: np.ndarray, aux: np.ndarray | None) -> None:
        g = self.grid
        reach = self.reinit_ring + 2
        if min(self.brick) < reach:
            raise InputError(
                f"bricks need at least reinit_ring + 2 = {reach} cells a side, not "
                f"{self.brick}: use larger bricks or a smaller reinit_ring"
            )
        # unstored places read as distances beyond every band (positive: the kernels only
        # need them outside the band), dense places of unstored bricks as FAR of their sign
        self.far = float(self.width + self.reinit_ring + 1)
        padded = g.pad(cells.astype(np.float64), "linear")
        bx, by, bz = self.brick
        pz, py, px = g.padded_shape
        self._places = (-(-pz // bz), -(-py // by), -(-px // bx))
        mid = padded[0][np.minimum(np.arange(self._places[0]) * bz + bz // 2, pz - 1)][
            :, np.minimum(np.arange(self._places[1]) * by + by // 2, py - 1)
        ][:, :, np.minimum(np.arange(self._places[2]) * bx + bx // 2, px - 1)]
        self._sign = np.where(mid < 0, -1, 1).astype(np.int8)  # (z, y, x) brick places
        self.bricks = BrickBand.from_coords(
            self.runtime, g.padded_shape, self._initial_coords(padded[0], reach), self.brick
        )
        self.cur = self._scatter(padded)
        self.nxt = self.cur.copy()
        self.ls0 = self.cur.copy()
        self.stage = cla.empty_like(self.cur)
        self._aux_padded = None if aux is None else g.pad(np.asarray(aux, np.float64)[None])
        self._aux_to_bricks()
        self._mask = cla.zeros(self.runtime.queue, self.bricks.plane, np.uint8)
        self._flag = cla.zeros(self.runtime.queue, 1, np.int32)
        rt = self.runtime
        defines = dict(SPEED=self.mode, NC=self.nc, RING=self.reinit_ring, BX=bx, BY=by, BZ=bz)
        k = {}
        k["bricks_euler"] = rt.kernel("regions/bricks.cl", "bricks_euler", g.dtype, **defines)
        k["bricks_heun"] = rt.kernel("regions/bricks.cl", "bricks_heun", g.dtype, **defines)
        k["bricks_advect"] = rt.kernel("regions/bricks.cl", "bricks_advect", g.dtype, **defines)
        k["bricks_extend"] = rt.kernel("regions/bricks.cl", "bricks_extend", g.dtype, **defines)
        k["bricks_targets"] = rt.kernel("regions/bricks.cl", "bricks_targets", g.dtype, **defines)
        k["bricks_reinit_stage"] = rt.kernel(
            "regions/bricks.cl", "bricks_reinit_stage", g.dtype, **defines
        )
        k["bricks_band_mask"] = rt.kernel(
            "regions/bricks.cl", "bricks_band_mask", g.dtype, **defines
        )
        k["bricks_flags"] = rt.kernel("regions/bricks.cl", "bricks_flags", g.dtype, **defines)
        k["bricks_remap"] = rt.kernel("regions/bricks.cl", "bricks_remap", g.dtype, **defines)
        self._k = k

    def _initial_coords(self, phi: np.ndarray, reach: int) -> np.ndarray:
        """The bricks the upkeep keeps for the initial Phi (padded): those holding a cell
        within `reach` cells (a cube) of an interior cell with |Phi| < width."""
        from scipy.ndimage import maximum_filter

        g = self.grid
        step = np.zeros(phi.shape, bool)
        inner = (slice(g.ghost, -g.ghost),) * 3
        step[inner] = np.abs(phi[inner]) < self.width
        needed = maximum_filter(step, size=2 * reach + 1, mode="constant")
        mz, my, mx = self._places
        bx, by, bz = self.brick
        full = np.zeros((mz * bz, my * by, mx * bx), bool)
        full[: phi.shape[0], : phi.shape[1], : phi.shape[2]] = needed
        cz, cy, cx = np.nonzero(full.reshape(mz, bz, my, by, mx, bx).any(axis=(1, 3, 5)))
        return np.stack([cx, cy, cz], axis=1)

    def _scatter(self, padded: np.ndarray) -> cla.Array:
        """Brick buffer of padded host values (channels, PZ, PY, PX); cells past the grid
        and the sentinel brick at FAR."""
        b = self.bricks
        flat = padded.reshape(padded.shape[0], -1)
        out = np.full((flat.shape[0], b.nbricks + 2, b.cells_per_brick), self.far, self.grid.dtype)
        valid = b.cells >= 0
        out[:, 1 : b.nbricks + 1][:, valid] = flat[:, b.cells[valid]]
        self.runtime.check_alloc(out.nbytes, "brick level sets")
        return cla.to_device(self.runtime.queue, out)

    def _aux_to_bricks(self) -> None:
        self.aux = self.cur if self._aux_padded is None else self._scatter(self._aux_padded)

    def set_aux(self, values: ArrayLike) -> None:
        self._aux_padded = self.grid.pad(np.asarray(values, np.float64)[None], "edge")
        self._aux_to_bricks()
        self._stats_fresh = False

    def padded(self, data: cla.Array, signed: bool = True) -> np.ndarray:
        """A brick buffer as dense padded host values (channels, PZ, PY, PX): the stored
        bricks, and FAR where no brick is stored, with the sign of its place (signed) or
        positive (what the kernels read there)."""
        g, b = self.grid, self.bricks
        bx, by, bz = self.brick
        pz, py, px = g.padded_shape
        channels = data.size // b.plane
        if signed:
            sign = self._sign.repeat(bz, 0).repeat(by, 1).repeat(bx, 2)[:pz, :py, :px]
            dense = np.broadcast_to(
                self.far * sign.astype(np.float64), (channels, pz, py, px)
            ).copy()
        else:
            dense = np.full((channels, pz, py, px), self.far)
        host = data.get().reshape(channels, b.nbricks + 2, b.cells_per_brick)
        valid = b.cells >= 0
        dense.reshape(channels, -1)[:, b.cells[valid]] = host[:, 1 : b.nbricks + 1][:, valid]
        return dense

    def volumes(self) -> tuple[np.ndarray, np.ndarray]:
        """(Phi, Phi-hats) in world units on the host (FAR cells of the right sign where no
        brick is stored)."""
        data = np.ascontiguousarray(self.grid.interior(self.padded(self.cur))) * self.h
        return data[0], data[1:]

    def memory(self) -> int:
        """Device bytes of the level sets' buffers (cur, nxt, ls0, stage) and the mask."""
        return 4 * self.cur.nbytes + self._mask.nbytes

    # ---- launches -----------------------------------------------------------------------------
    def _geometry(self, n: int | None = None) -> tuple[int, int]:
        """(work-items, bricks each) of a launch over n bricks (default: every brick)."""
        return self.runtime.brick_items(self.bricks.nbricks if n is None else n)

    def _launch(self, name: str, *args) -> None:
        items, per = self._geometry()
        b = self.bricks
        self._k[name](
            self.runtime.queue,
            (items,),
            (1,),
            *args,
            b.nbr.data,
            b.brick_bits.data,
            np.int32(b.nbricks),
            np.int32(b.plane),
            np.int32(per),
        )

    # ---- bands and upkeep ---------------------------------------------------------------------
    def rebuild(self) -> None:
        """The upkeep (bricks added and dropped), then the band masks, from the current Phi."""
        g, q = self.grid, self.runtime.queue
        dims = (
            g.scalar(self.width),
            np.int32(g.nx),
            np.int32(g.ny),
            np.int32(g.nz),
            np.int32(g.ghost),
        )
        coords_dev = self._coords_on_device()
        flags = cla.empty(q, max(self.bricks.nbricks, 1), np.int32)
        items, per = self._geometry()
        self._k["bricks_flags"](
            q,
            (items,),
            (1,),
            self.cur.data,
            flags.data,
            coords_dev.data,
            *dims,
            np.int32(self.bricks.nbricks),
            np.int32(per),
        )
        words = flags.get()[: self.bricks.nbricks]
        if not np.any(words & (1 << 13)):
            raise InputError(
                "the surface vanished (Phi has no zero level set left on the grid); "
                "track for a shorter time"
            )
        if self._upkeep(words):
            coords_dev = self._coords_on_device()
        # the work buffers equal cur on every brick no kernel writes (see regions/bricks.cl)
        cl.enqueue_copy(q, self.nxt.data, self.cur.data)
        self._mask = cla.zeros(q, self.bricks.plane, np.uint8)
        with self.runtime.lock:
            self._flag.fill(0)
        items, per = self._geometry()
        self._k["bricks_band_mask"](
            q,
            (items,),
            (1,),
            self.cur.data,
            self._mask.data,
            self.bricks.brick_bits.data,
            coords_dev.data,
            self._flag.data,
            *dims,
            self.bricks.nbr.data,
            np.int32(self.bricks.nbricks),
            np.int32(per),
        )
        self._stats = cla.zeros(q, 2 * items, g.dtype)
        self._stats_fresh = False
        if self._flag.get()[0]:
            raise InputError(
                f"the surface came within {self.width + self.reinit_ring + 1:.0f} cells of the "
                f"volume's border at t = {self.time:g}: pad phi (and the other volumes) with "
                f"more cells"
            )

    def _coords_on_device(self) -> cla.Array:
        """The bricks' coordinates, with zero rows for the sentinel and the spare brick."""
        zero = np.zeros((1, 3), np.int32)
        return cla.to_device(
            self.runtime.queue, np.concatenate([zero, self.bricks.coords, zero]).astype(np.int32)
        )

    def _upkeep(self, words: np.ndarray) -> bool:
        """Store exactly the bricks the flag words name; whether the set changed."""
        old = self.bricks.coords
        n = len(old)
        source, direction = np.nonzero((words[:, None] >> np.arange(27)) & 1)
        cand = old[source] + OFFSETS[direction]
        mz, my, mx = self._places
        inside = np.all((cand >= 0) & (cand < np.array([mx, my, mz])), axis=1)
        cand, source, direction = cand[inside], source[inside], direction[inside]
        key = (cand[:, 2].astype(np.int64) * my + cand[:, 1]) * mx + cand[:, 0]
        old_key = (old[:, 2].astype(np.int64) * my + old[:, 1]) * mx + old[:, 0]
        new_key, first = np.unique(key, return_index=True)
        kept = np.isin(old_key, new_key)
        if kept.all() and len(new_key) == n:
            return False
        gone = old[~kept]
        self._sign[gone[:, 2], gone[:, 1], gone[:, 0]] = np.where(
            words[~kept] & (1 << SIGN_BIT), -1, 1
        )
        band = BrickBand.from_coords(self.runtime, self.grid.padded_shape, cand[first], self.brick)
        # where each new brick's values come from: the old brick itself (kept), else the
        # brick that flagged it first and the direction from there
        place = band.coords
        pkey = (place[:, 2].astype(np.int64) * my + place[:, 1]) * mx + place[:, 0]
        order = np.argsort(old_key)
        at = np.minimum(np.searchsorted(old_key[order], pkey), max(n - 1, 0))
        was = old_key[order][at] == pkey
        src = np.zeros(band.nbricks + 2, np.int32)
        dirs = np.full(band.nbricks + 2, -1, np.int32)
        src[1:-1] = np.where(was, order[at] + 1, source[first][np.searchsorted(new_key, pkey)] + 1)
        dirs[1:-1] = np.where(was, -1, direction[first][np.searchsorted(new_key, pkey)])
        q = self.runtime.queue
        out = cla.empty(q, self.nc * band.plane, self.grid.dtype)
        self.runtime.check_alloc(out.nbytes, "brick level sets")
        items, per = self._geometry(band.nbricks)
        self._k["bricks_remap"](
            q,
            (items,),
            (1,),
            self.cur.data,
            out.data,
            cla.to_device(q, src).data,
            cla.to_device(q, dirs).data,
            self.grid.scalar(self.far),
            self.grid.scalar(self.far),
            np.int32(self.bricks.plane),
            np.int32(band.plane),
            np.int32(band.nbricks),
            np.int32(per),
        )
        self.bricks = band
        self.cur = out
        self.nxt = cla.empty_like(out)
        self.ls0 = cla.empty_like(out)
        self.stage = cla.empty_like(out)
        self._aux_to_bricks()
        return True

    def band_sizes(self) -> tuple[int, int]:
        """(step band cells, reinitialisation band cells), counted on the host (tests and
        benchmarks)."""
        m = self._mask.get()
        return int(np.count_nonzero(m & BIT_STEP)), int(np.count_nonzero(m & BIT_REINIT))

    def band_masks(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense interior masks (step band, reinitialisation band, stored cells), for tests."""
        g, b = self.grid, self.bricks
        m = self._mask.get().reshape(b.nbricks + 2, b.cells_per_brick)[1 : b.nbricks + 1]
        out = np.zeros((3,) + g.padded_shape, bool)
        valid = b.cells >= 0
        flat = out.reshape(3, -1)
        cells = b.cells[valid]
        flat[0, cells] = (m[valid] & BIT_STEP) != 0
        flat[1, cells] = (m[valid] & BIT_REINIT) != 0
        flat[2, cells] = True
        gh = g.ghost
        return tuple(o[gh:-gh, gh:-gh, gh:-gh] for o in out)

    # ---- reinitialisation and steps -----------------------------------------------------------
    def reinitialize(self, iterations: int | None = None, extension: int | None = None) -> None:
        g, q = self.grid, self.runtime.queue
        its = self.reinit_iterations if iterations is None else int(iterations)
        ext = EXTEND_ITERATIONS if extension is None else int(extension)
        keep, full = (g.scalar(d) for d in EXTEND_FROM)
        for _ in range(ext if its else 0):
            self._launch(
                "bricks_extend",
                self.cur.data,
                self._mask.data,
                self.nxt.data,
                g.scalar(EXTEND_DT),
                keep,
                full,
            )
            self.cur, self.nxt = self.nxt, self.cur
        cl.enqueue_copy(q, self.ls0.data, self.cur.data)
        if its:
            self._launch("bricks_targets", self.ls0.data, self._mask.data, self.stage.data)
        for _ in range(its):
            for src, dst, second in ((self.cur, self.nxt, 0), (self.nxt, self.cur, 1)):
                self._launch(
                    "bricks_reinit_stage",
                    src.data,
                    self.ls0.data,
                    self.stage.data,
                    dst.data,
                    self._mask.data,
                    g.scalar(REINIT_DT),
                    np.int32(second),
                )
        self.rebuild()
        self.reinits += 1
        self._moved = 0.0

    def _speed_bound(self) -> float:
        if not self._stats_fresh:
            # the Euler stage with dt = 0 writes the speeds' bound and nxt = cur (scratch)
            self._stage("bricks_euler", self.cur, self.nxt, 0.0)
            return float(self._stats.get()[: len(self._stats) // 2].max())
        return float(self._stats.get().max())

    def _stage(self, name, src, dst, dt) -> None:
        g = self.grid
        self._launch(
            name,
            src.data,
            self.aux.data,
            dst.data,
            self._stats.data,
            self._mask.data,
            g.scalar(dt),
            g.scalar(1e-12),
            *self._cutoff(),
            g.scalar(self.scale),
            g.scalar(self.vmax),
        )

    def _advect(self, src, dst, dt, second) -> None:
        g, u = self.grid, self.velocity
        self._launch(
            "bricks_advect",
            src.data,
            dst.data,
            self._mask.data,
            g.scalar(dt),
            g.scalar(u[0]),
            g.scalar(u[1]),
            g.scalar(u[2]),
            *self._cutoff(),
            np.int32(second),
        )

    def step(self, dt: float) -> None:
        if self.velocity is None:
            self._stage("bricks_euler", self.cur, self.nxt, dt)
            self._stage("bricks_heun", self.nxt, self.cur, dt)
            self._stats_fresh = True
        else:
            self._advect(self.cur, self.nxt, dt, 0)
            self._advect(self.nxt, self.cur, dt, 1)
        self.time += dt
        self.steps += 1
