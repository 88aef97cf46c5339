"""Narrow-band storage: the table each band user chooses its storage from (`StorageTable`),
and dense bricks (the layout kernels/bricks/bricks.h; the surfaces' and regions' steps on it
are in their own kernels/surface/bricks.cl and kernels/regions/bricks.cl).

The padded grid of a Grid3D is cut into bricks of BX x BY x BZ cells (a compile-time size:
8x8x8, 8x4x4 and 4x4x4 were compared in docs/surface_storage.md). Only the bricks the band needs
are stored, in Morton order of their brick coordinates, so bricks near in space are near in
memory. On the device:

- one buffer per quantity, `(channels, nbricks + 2, BV)` with BV = BX BY BZ cells a brick, x
  fastest inside a brick; the stored bricks are 1..nbricks, brick 0 is a sentinel of zeros
  that stands for every brick not stored (brick nbricks + 1 is spare). The stepped values,
  which the closest-point re-extension gathers, have each brick lengthened along x, y and z
  by an apron of APRON cells, copies of the next bricks' first ones, so a tricubic stencil
  never leaves the brick of its first node (the step writes both). psi, which is fixed, is
  stored as tiles of halo 2 (`tiles`, gathered on the device from the surface's padded psi),
  what the steps read around a brick;
- `nbr`: per brick the indices of its 27 neighbours (itself in the middle, the sentinel where
  none is stored), for the step, which reads u with its neighbours' faces (no halo is
  stored for data), and for the aprons it writes;
- `node_rows`: per brick and row along x, whether it holds a node (the step skips the others);
- `brick_bits`: per brick the union of its cells' band bits (NODE: the step updates the
  cell, REACH: re-extended after every step, EXT: re-extended when a flow returns); the
  kernels skip bricks without the bits they update. The per-cell bits (`mask_host`) stay on
  the host, where `gather` reads only the cells that carry meaning; the re-extension visits
  lists of its cells, in the order of their stencils' first nodes.
On the host, `map_host` is the coarse brick-index map of the whole padded grid (one int per
brick place, the sentinel where none is stored): it turns the closest points' first nodes,
which may lie many bricks away, into brick-storage places (`index_of`, `node_code`).

Dense numpy arrays go in and out through `scatter` and `gather` (users' contract).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cla

from .errors import ClpdeError, InputError

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("bricks/tiles.cl",)

NODE, REACH, EXT = 1, 2, 4
# Cells of the next brick's rows kept after each row of the re-extension's source (bricks.cl)
APRON = 3
# Sizes compared (benchmarks/surface_accuracy.py --sections 6); the default was the fastest
# over the grids measured, and its aprons cost the least memory (docs/surface_storage.md).
BRICK_SIZES = ((4, 4, 4), (8, 4, 4), (8, 8, 8))
DEFAULT_BRICK = (8, 8, 8)


class StorageTable(dict):
    """Storage name -> the class that holds a band in it, one table per band user: tracking's
    2D band (tracking/storage.py), a surface flow's data (surface/storage.py) and the region
    tracker (regions/api.py). Each class of a table has the same interface as the others of
    that table, so the user's code runs in any of them without asking which; `choose` is the
    one check of a storage name."""

    def choose(self, name: str):
        """The class of storage `name`; an InputError naming the table's storages if none."""
        if not isinstance(name, str) or name not in self:
            raise InputError(f"storage must be one of {', '.join(map(repr, self))}, not {name!r}")
        return self[name]


def morton_key(bx: np.ndarray, by: np.ndarray, bz: np.ndarray) -> np.ndarray:
    """Interleaved bits (x lowest) of brick coordinates below 2^21."""
    key = np.zeros(bx.shape, np.uint64)
    for bit in range(21):
        for axis, c in enumerate((bx, by, bz)):
            key |= ((c.astype(np.uint64) >> np.uint64(bit)) & np.uint64(1)) << np.uint64(
                3 * bit + axis
            )
    return key


def _brick_cells(coords, brick, padded_shape, apron: int, halo: int = 0) -> np.ndarray:
    """(nbricks, (BZ + a) (BY + a) (BX + a)) flat padded index of every cell of the bricks
    lengthened along each axis by `apron` cells of the next brick places and `halo` cells on
    both sides (a = apron + 2 halo); -1 outside the grid.

    A brick's first cell plus each cell's offset (one int64 add per cell); the per-axis
    tests run only for the bricks whose lengthened box leaves the grid (faster than testing
    every cell: docs/surface_storage.md)."""
    bx, by, bz = brick
    pz, py, px = padded_shape
    a = apron + 2 * halo
    lz, ly, lx = np.meshgrid(np.arange(bz + a), np.arange(by + a), np.arange(bx + a), indexing="ij")
    lz, ly, lx = lz.ravel(), ly.ravel(), lx.ravel()
    c = coords.astype(np.int64)
    z0, y0, x0 = c[:, 2] * bz - halo, c[:, 1] * by - halo, c[:, 0] * bx - halo
    out = ((z0 * py + y0) * px + x0)[:, None] + ((lz * py + ly) * px + lx)[None, :]
    edge = np.flatnonzero(
        (z0 < 0)
        | (y0 < 0)
        | (x0 < 0)
        | (z0 + bz + a > pz)
        | (y0 + by + a > py)
        | (x0 + bx + a > px)
    )
    if edge.size:
        z, y, x = z0[edge, None] + lz, y0[edge, None] + ly, x0[edge, None] + lx
        inside = (z >= 0) & (y >= 0) & (x >= 0) & (z < pz) & (y < py) & (x < px)
        out[edge] = np.where(inside, out[edge], -1)
    return out


def _fill_bricks(out: np.ndarray, flat: np.ndarray, cells: np.ndarray) -> None:
    """out[:, 1 : nbricks + 1] = the values of flat (channels, cells) at `cells` (from
    _brick_cells), zero where a cell lies outside the grid. Gathers by np.take, one channel
    at a time (boolean masks over every cell were slower: docs/surface_storage.md)."""
    outside = np.nonzero(cells < 0)
    idx = np.where(cells < 0, 0, cells) if outside[0].size else cells
    for c in range(flat.shape[0]):
        dst = out[c, 1 : cells.shape[0] + 1]
        dst[...] = flat[c].take(idx)
        dst[outside] = 0


def dilate_axes(mask: np.ndarray, reach: int) -> np.ndarray:
    """mask grown by up to `reach` cells along each axis separately (not diagonally)."""
    out = mask.copy()
    for axis in range(3):
        m = np.moveaxis(mask, axis, 0)
        o = np.moveaxis(out, axis, 0)
        for d in range(1, reach + 1):
            o[d:] |= m[:-d]
            o[:-d] |= m[d:]
    return out


def brick_neighbours(coords: np.ndarray) -> np.ndarray:
    """(n, 27) the 1-based index of each brick's 27 neighbours ((dz, dy, dx) in -1..1, x
    fastest) among `coords` (n, 3), 0 where none is stored: the neighbours' keys looked up
    in the sorted keys of the bricks (n log n, whatever the grid's size)."""
    c = np.asarray(coords, np.int64) + 1  # neighbours' coordinates stay >= 0
    span = int(c.max(initial=0)) + 2

    def key(a):
        return (a[..., 2] * span + a[..., 1]) * span + a[..., 0]

    keys = key(c)
    order = np.argsort(keys)
    ranked = keys[order]
    d = np.arange(-1, 2)
    dz, dy, dx = np.meshgrid(d, d, d, indexing="ij")
    offsets = np.stack([dx.ravel(), dy.ravel(), dz.ravel()], axis=1)
    want = key(c[:, None, :] + offsets[None])
    at = np.minimum(np.searchsorted(ranked, want), max(len(ranked) - 1, 0))
    if not len(ranked):
        return np.zeros((0, 27), np.int32)
    found = ranked[at] == want
    return np.where(found, order[at] + 1, 0).astype(np.int32)


@dataclass
class BrickBand:
    """Bricks covering a band of a padded grid, with their tables on the device."""

    runtime: object
    padded_shape: tuple[int, int, int]
    brick: tuple[int, int, int]
    coords: np.ndarray  # (nbricks, 3) brick coordinates (x, y, z), Morton order
    cells: np.ndarray  # (nbricks, BV) flat padded index of each brick cell, -1 past the grid
    # (row i describes brick i + 1)
    map_shape: tuple[int, int, int]
    nbr: cla.Array
    mask_host: np.ndarray | None  # (nbricks + 2, BV) band bits (brick 0: the sentinel)
    brick_bits: cla.Array  # per brick the OR of its cells' bits
    node_rows: cla.Array | None  # (nbricks + 2, BZ, BY): 1 where the row along x holds a node
    map_host: np.ndarray | None

    @property
    def nbricks(self) -> int:
        return len(self.coords)

    @property
    def cells_per_brick(self) -> int:
        bx, by, bz = self.brick
        return bx * by * bz

    @property
    def plane(self) -> int:
        """Channel stride of a brick buffer (the sentinel included)."""
        return (self.nbricks + 2) * self.cells_per_brick

    @property
    def apron_plane(self) -> int:
        """Channel stride of a brick buffer in the apron layout (bricks lengthened by APRON
        cells along x, y and z; the sentinel included)."""
        bx, by, bz = self.brick
        return (self.nbricks + 2) * (bx + APRON) * (by + APRON) * (bz + APRON)

    @property
    def stored_cells(self) -> int:
        return self.nbricks * self.cells_per_brick

    def defines(self) -> dict:
        bx, by, bz = self.brick
        return {"BX": bx, "BY": by, "BZ": bz}

    @classmethod
    def build(
        cls, runtime, padded_shape, stored: np.ndarray, bits: np.ndarray, brick=DEFAULT_BRICK
    ) -> BrickBand:
        """Bricks holding every True cell of `stored` (padded grid), with per-cell `bits`."""
        bx, by, bz = (int(b) for b in brick)
        if min(bx, by, bz) < 4 or max(bx, by, bz) > 16:
            raise ValueError(
                "bricks need 4 to 16 cells a side (a tricubic stencil spans at most "
                "2 bricks; node_code keeps 4 bits an axis)"
            )
        pz, py, px = padded_shape
        # one brick place more than needed on each axis: a gather's "next brick" always exists
        mz, my, mx = -(-pz // bz) + 1, -(-py // by) + 1, -(-px // bx) + 1
        full = np.zeros((mz * bz, my * by, mx * bx), bool)
        full[:pz, :py, :px] = stored
        occupied = full.reshape(mz, bz, my, by, mx, bx).any(axis=(1, 3, 5))
        cz, cy, cx = np.nonzero(occupied)
        order = np.argsort(morton_key(cx, cy, cz), kind="stable")
        coords = np.stack([cx, cy, cz], axis=1)[order].astype(np.int32)
        n = len(coords)
        bmap = np.zeros((mz, my, mx), np.int32)
        bmap[coords[:, 2], coords[:, 1], coords[:, 0]] = np.arange(1, n + 1, dtype=np.int32)
        # 27 neighbours, (dz, dy, dx) in -1..1, x fastest
        d = np.arange(-1, 2)
        dz, dy, dx = np.meshgrid(d, d, d, indexing="ij")
        nz_ = coords[:, 2, None] + dz.ravel()
        ny_ = coords[:, 1, None] + dy.ravel()
        nx_ = coords[:, 0, None] + dx.ravel()
        inside = (nz_ >= 0) & (ny_ >= 0) & (nx_ >= 0) & (nz_ < mz) & (ny_ < my) & (nx_ < mx)
        nbr = np.zeros((n + 2, 27), np.int32)
        nbr[1 : n + 1][inside] = bmap[nz_[inside], ny_[inside], nx_[inside]]
        cells = _brick_cells(coords, (bx, by, bz), padded_shape, 0)
        valid = cells >= 0
        mask_host = np.zeros((n + 2, bx * by * bz), np.uint8)
        flat_bits = bits.reshape(-1)
        mask_host[1 : n + 1][valid] = flat_bits[cells[valid]]
        q = runtime.queue
        rows = (mask_host.reshape(n + 2, bz, by, bx) & NODE).any(axis=3).astype(np.uint8)
        dev = {
            name: cla.to_device(q, np.ascontiguousarray(a))
            for name, a in (
                ("nbr", nbr),
                ("bits", np.bitwise_or.reduce(mask_host, axis=1)),
                ("rows", rows),
            )
        }
        return cls(
            runtime,
            tuple(padded_shape),
            (bx, by, bz),
            coords,
            cells,
            (mz, my, mx),
            dev["nbr"],
            mask_host,
            dev["bits"],
            dev["rows"],
            bmap,
        )

    @classmethod
    def from_coords(
        cls, runtime, padded_shape, coords: np.ndarray, brick=DEFAULT_BRICK
    ) -> BrickBand:
        """Bricks at the brick coordinates `coords` ((n, 3), x y z), put in Morton order,
        with the neighbour table found from the coordinates alone (brick_neighbours: work
        in proportion to the bricks, no map of the grid), for a band kept on the device
        (regions_bricks.py): the per-cell band bits and the coarse map stay empty."""
        coords = np.asarray(coords, np.int32).reshape(-1, 3)
        order = np.argsort(morton_key(coords[:, 0], coords[:, 1], coords[:, 2]), kind="stable")
        coords = np.ascontiguousarray(coords[order])
        n = len(coords)
        bz, by, bx = brick[2], brick[1], brick[0]
        pz, py, px = padded_shape
        nbr = np.zeros((n + 2, 27), np.int32)
        nbr[1 : n + 1] = brick_neighbours(coords)
        q = runtime.queue
        return cls(
            runtime,
            tuple(padded_shape),
            tuple(int(b) for b in brick),
            coords,
            _brick_cells(coords, brick, padded_shape, 0),
            (-(-pz // bz), -(-py // by), -(-px // bx)),
            cla.to_device(q, nbr),
            None,
            cla.zeros(q, n + 2, np.uint8),
            None,
            None,
        )

    @property
    def cell_bits(self) -> cla.Array:
        """mask_host on the device (per stored cell its band bits), uploaded when first asked
        (TV's dynamic lambda sums over the nodes)."""
        if getattr(self, "_cell_bits", None) is None:
            self._cell_bits = cla.to_device(self.runtime.queue, self.mask_host)
        return self._cell_bits

    def _places(self, flat: np.ndarray):
        """(brick, z, y, x) of cells given by flat padded indices: the brick-storage index of
        their brick (the sentinel, 0, where none is stored) and their place in it. int32
        throughout: on big grids the int64 version's temporaries cost many times more in
        first-touch page faults (docs/surface_storage.md)."""
        _, py, px = self.padded_shape
        bx, by, bz = (np.int32(b) for b in self.brick)
        z, rem = np.divmod(np.asarray(flat, np.int32), np.int32(py * px))
        y, x = np.divmod(rem, np.int32(px))
        zb, z = np.divmod(z, bz)
        yb, y = np.divmod(y, by)
        xb, x = np.divmod(x, bx)
        return self.map_host[zb, yb, xb], z, y, x

    def index_of(self, flat: np.ndarray, apron: int = 0) -> np.ndarray:
        """Brick-storage indices (int32) of cells given by flat padded indices, in the
        layout with bricks lengthened by `apron` (cells in bricks not stored land in the
        sentinel, brick 0)."""
        bx, by, bz = self.brick
        ax, ay, az = bx + apron, by + apron, bz + apron
        if (self.nbricks + 2) * ax * ay * az >= 2**31:
            raise ClpdeError(
                f"{self.nbricks} bricks are more than 32-bit indices address; use a coarser grid"
            )
        b, z, y, x = self._places(flat)
        return b * np.int32(ax * ay * az) + (z * np.int32(ay) + y) * np.int32(ax) + x

    def node_code(self, flat: np.ndarray) -> np.ndarray:
        """The first interpolation nodes of closest points (flat padded indices) coded for
        bricks.cl's re-extension: brick << 12 | z << 8 | y << 4 | x, the node's place in its
        brick (a code, not an index, saves the kernel three divisions)."""
        if self.nbricks >= 2**19:
            raise ClpdeError(
                f"{self.nbricks} bricks are more than the re-extension's node code "
                "holds (2^19); use a larger brick size"
            )
        b, z, y, x = self._places(flat)
        return (b << 12) | (z << 8) | (y << 4) | x

    # ---- dense <-> bricks ---------------------------------------------------------------------
    def scatter_tiles(self, padded: np.ndarray, dtype, halo: int) -> cla.Array:
        """Device tiles (channels, nbricks + 2, BZ + 2 halo, BY + 2 halo, BX + 2 halo) of
        padded values: each brick with the cells within `halo` of its faces (for fixed
        quantities, read by every step: psi)."""
        flat = np.asarray(padded).reshape(padded.shape[0], -1)
        cells = _brick_cells(self.coords, self.brick, self.padded_shape, 0, halo)
        out = np.zeros((flat.shape[0], self.nbricks + 2, cells.shape[1]), dtype)
        _fill_bricks(out, flat, cells)
        self.runtime.check_alloc(out.nbytes, "brick tiles")
        return cla.to_device(self.runtime.queue, out)

    def tiles(self, padded: cla.Array, halo: int) -> cla.Array:
        """scatter_tiles of a device volume (channels, PZ, PY, PX), on the device
        (kernels/bricks/tiles.cl): psi's tiles without a host gather of the dense grid."""
        rt, q = self.runtime, self.runtime.queue
        nc = padded.shape[0]
        bx, by, bz = self.brick
        cells = (bx + 2 * halo) * (by + 2 * halo) * (bz + 2 * halo)
        out = cla.zeros(q, (nc, self.nbricks + 2, cells), padded.dtype)
        if self.nbricks:
            rt.check_alloc(out.nbytes, "brick tiles")
            coords = cla.to_device(q, np.ascontiguousarray(self.coords, np.int32))
            pz, py, px = self.padded_shape
            rt.kernel("bricks/tiles.cl", "tiles_from_dense", padded.dtype, **self.defines())(
                q,
                *rt.items(self.nbricks * cells, nc),
                padded.data,
                out.data,
                coords.data,
                np.int32(self.nbricks),
                np.int32(halo),
                np.int32(px),
                np.int32(py),
                np.int32(pz),
            )
        return out

    def scatter(self, padded: np.ndarray, dtype, apron: int = 0) -> cla.Array:
        """Device brick buffer (channels, nbricks + 2, BZ + apron, BY + apron, BX + apron)
        from padded (channels, PZ, PY, PX); the apron holds the first cells of the next brick
        places (the re-extension's source, whose stencils then never leave a brick). The flows
        make their apron layout on the device (bricks.cl's bricks_to_apron, tested against
        this one)."""
        flat = np.asarray(padded).reshape(padded.shape[0], -1)
        bx, by, bz = self.brick
        cells = (
            self.cells
            if apron == 0
            else _brick_cells(self.coords, self.brick, self.padded_shape, apron)
        )
        out = np.zeros(
            (flat.shape[0], self.nbricks + 2, (bx + apron) * (by + apron) * (bz + apron)), dtype
        )
        _fill_bricks(out, flat, cells)
        self.runtime.check_alloc(out.nbytes, "brick volume")
        return cla.to_device(self.runtime.queue, out)

    def gather(self, data: cla.Array, into: np.ndarray, bits: int = EXT) -> np.ndarray:
        """Write the brick values of the cells carrying `bits` into padded `into`
        (channels, PZ, PY, PX), in place; returns it."""
        host = data.get().reshape(into.shape[0], self.nbricks + 2, self.cells_per_brick)
        keep = (self.mask_host[1 : self.nbricks + 1] & bits) != 0
        flat = into.reshape(into.shape[0], -1)
        flat[:, self.cells[keep]] = host[:, 1 : self.nbricks + 1][:, keep]
        return into

    def launch_list(self, kernel, n: int, *args):
        """Run a LIST_RANGE kernel (common.h) over n entries."""
        if n == 0:
            return None
        (gsize,), (lsize,), run = self.runtime.list_launch(n)
        return kernel(
            self.runtime.queue,
            (gsize, 1),
            (lsize, 1),
            *args,
            np.int32(n),
            np.int32(self.plane),
            np.int32(run),
        )

    def launch(self, kernel, *args, channels: int = 1):
        """Run a brick kernel over every brick: on CPUs a work-item walks whole bricks
        (bricks_per_item of them), on GPUs a work-group of BV work-items takes one brick."""
        n = self.nbricks
        if n == 0:
            return None
        rt = self.runtime
        if rt.is_cpu:
            items, per = rt.brick_items(n)
            gsize, lsize = (items, channels), (1, 1)
        else:
            per = 1
            gsize, lsize = (n * self.cells_per_brick, channels), (self.cells_per_brick, 1)
        return kernel(
            rt.queue,
            gsize,
            lsize,
            *args,
            self.nbr.data,
            self.brick_bits.data,
            np.int32(n),
            np.int32(self.plane),
            np.int32(per),
        )
