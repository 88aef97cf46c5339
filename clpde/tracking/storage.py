"""How a 2D level set's band is laid out on the device (docs/tracking.md, "2D bricks,
measured"): CellList, a compacted list of the band's cells, or Bricks, the bricks of BX x BY
cells of the frame that hold a band cell (kernels/bricks/bricks2d.h). Both give the cells of a
mask, build a band kernel, launch it and count its work the same way, so `LevelSet` and the
flows stepped on it (morph.py) run in either through the one object that STORAGES names.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cla

from ..bricks import StorageTable
from ..fields import IndexList, compact

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/levelset.cl",)


@dataclass
class BrickSet:
    """The bricks of the movable region holding a cell where `mask` is nonzero (their
    indices bx + nbx by, in increasing order, built on the device)."""

    ids: cla.Array
    n: int
    mask: cla.Array


class CellList:
    """The band as a compacted list of its cells (an IndexList): a work-item per cell."""

    # the band kernels of this storage: what each step is called in the .cl files
    KERNELS = {
        "reinit": "levelset_reinit_step_list",
        "morph": "features_morph_track",
        "adaptive": "adaptive_morph_adaptive",
    }

    def __init__(self, grid, margin: int, group_per_brick: bool):
        self.grid, self.runtime, self.margin = grid, grid.runtime, margin
        self.group_per_brick = group_per_brick

    def cells(self, mask: cla.Array) -> IndexList:
        """The cells where a padded device mask is nonzero."""
        return compact(self.runtime, mask)

    def kernel(self, filename: str, name: str, **defines):
        """A band kernel of this storage (`name` one of KERNELS' values)."""
        return self.grid.kernel(filename, name, **defines)

    def morph_kernel(self, discrepancy: str) -> str:
        """The morphing step's kernel (features.cl) for a discrepancy."""
        return self.KERNELS["morph"]

    def reinit_args(self, cells, dt) -> tuple:
        """The reinitialisation step's arguments after its three fields."""
        return self.grid.scalar(dt), np.int32(self.grid.sx)

    def parts(self, cells) -> int:
        """Work-items of a launch over `cells`: the length of its per-item statistics."""
        return self.runtime.list_launch(max(cells.n, 1))[0][0]

    def launch(self, kernel, cells, *args):
        """Run a band kernel over `cells` (n > 0)."""
        return self.grid.launch_list(kernel, cells, *args)

    def stored(self, cells) -> int:
        """Cells a launch over `cells` visits."""
        return cells.n


class Bricks(CellList):
    """The band as the bricks of BX x BY cells (`brick`: 8 x 8 here) over the movable region
    that hold one of its cells (BrickSet): a work-group per brick (GPUs) or bricks walked
    whole by one work-item (CPUs)."""

    KERNELS = {
        "reinit": "levelset_reinit_step_bricks",
        "morph": "features_morph_track_bricks",
        "adaptive": "adaptive_morph_adaptive_bricks",
    }
    brick = (8, 8)

    def _geometry(self):
        """(nbx, nby, x0, y0, x1, y1): the bricks over the movable region, its padded
        corners."""
        bx, by = self.brick
        g, m = self.grid, self.margin
        x0, y0 = g.ghost + m, g.ghost + m
        x1, y1 = g.ghost + g.nx - m, g.ghost + g.ny - m
        return -(-(x1 - x0) // bx), -(-(y1 - y0) // by), x0, y0, x1, y1

    def cells(self, mask: cla.Array) -> BrickSet:
        nbx, nby, *corners = self._geometry()
        flags = cla.empty(self.runtime.queue, nbx * nby, np.uint8)
        self.kernel("tracking/levelset.cl", "levelset_mark_bricks")(
            self.runtime.queue,
            *self.runtime.items(nbx * nby),
            mask.data,
            flags.data,
            np.int32(nbx),
            np.int32(nby),
            *(np.int32(c) for c in corners),
            np.int32(self.grid.sx),
        )
        ids = compact(self.runtime, flags)
        return BrickSet(ids.indices, ids.n, mask)

    def kernel(self, filename: str, name: str, **defines):
        """A band kernel built for this brick size and launch geometry."""
        bx, by = self.brick
        defines.update(BX=bx, BY=by, GROUP_PER_BRICK=int(self.group_per_brick))
        return self.grid.kernel(filename, name, **defines)

    def morph_kernel(self, discrepancy: str) -> str:
        """With bricks walked by one work-item, the NCC slides its window sums over each
        brick (features_morph_track_tiled: faster than the cell-by-cell sums,
        docs/tracking.md; equal to rounding)."""
        if discrepancy == "ncc" and not self.group_per_brick:
            return "features_morph_track_tiled"
        return self.KERNELS["morph"]

    def reinit_args(self, cells, dt) -> tuple:
        return cells.mask.data, self.grid.scalar(dt)

    def _items(self, n: int):
        """(global size, local size, bricks per work-item) for n bricks."""
        cells = self.brick[0] * self.brick[1]
        if self.group_per_brick:
            return n * cells, cells, 1
        items, per = self.runtime.brick_items(n)
        return items, 1, per

    def parts(self, cells) -> int:
        return self._items(max(cells.n, 1))[0]

    def launch(self, kernel, cells, *args):
        gsize, lsize, per = self._items(cells.n)
        nbx, _, *corners = self._geometry()
        return kernel(
            self.runtime.queue,
            (gsize,),
            (lsize,),
            *args,
            cells.ids.data,
            np.int32(cells.n),
            np.int32(nbx),
            *(np.int32(c) for c in corners),
            np.int32(self.grid.sx),
            np.int32(per),
        )

    def stored(self, cells) -> int:
        return cells.n * self.brick[0] * self.brick[1]


class Bricks16x4(Bricks):
    """Bricks of 16 x 4 cells (measured against 8 x 8 in docs/tracking.md)."""

    brick = (16, 4)


# storage name -> the band's layout (TrackOptions.storage); StorageTable.choose checks a name
STORAGES = StorageTable(lists=CellList, bricks8x8=Bricks, bricks16x4=Bricks16x4)
