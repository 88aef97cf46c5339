"""The plan of method="spectral" (spectral.py), made on the host from the mask alone before
anything runs: the block grid over the damage, each block's size (a block whose window sees
too few known pixels is cut in four), and the waves, the order in which the blocks are
filled.

- A wave is every pending block that comes first, by its share of known pixels in its window
  (pixels filled by earlier blocks count `delta`), among the blocks its window touches. The
  blocks of a wave are independent, so the device runs a wave in one launch and never waits
  for the host between waves.
- Sums over windows are read from summed-area tables, so the plan costs a few passes over
  the damage's bounding box, not one per block.
"""

from __future__ import annotations

import numpy as np

MAXL = 32  # kernels/inpainting/spectral.cl's SPECTRAL_MAXL: the widest window


def _table(weight: np.ndarray) -> np.ndarray:
    """The summed-area table of `weight` ((rows, cols) integers) with a row and a column of
    zeros before it: entry [y, x] sums weight[:y, :x]."""
    sat = np.zeros((weight.shape[0] + 1, weight.shape[1] + 1), np.int64)
    np.cumsum(weight, 0, dtype=np.int64, out=sat[1:, 1:])
    np.cumsum(sat[1:, 1:], 1, out=sat[1:, 1:])
    return sat


def _box_sums(sat: np.ndarray, y0, y1, x0, x1):
    """Sums over rows [y0, y1), columns [x0, x1) of the array whose _table is `sat`, and
    the count of those pixels inside the array (outside counts 0; an empty range sums to
    0): integers, exact."""
    ny, nx = sat.shape[0] - 1, sat.shape[1] - 1
    y1, x1 = np.maximum(y1, y0), np.maximum(x1, x0)
    # (np.minimum of np.maximum: np.clip's checks cost more than the sums here)
    a_y, b_y = np.minimum(np.maximum(y0, 0), ny), np.minimum(np.maximum(y1, 0), ny)
    a_x, b_x = np.minimum(np.maximum(x0, 0), nx), np.minimum(np.maximum(x1, 0), nx)
    sums = sat[b_y, b_x] - sat[a_y, b_x] - sat[b_y, a_x] + sat[a_y, a_x]
    return sums, (b_y - a_y) * (b_x - a_x)


def _known_sums(hole_sat: np.ndarray, border: int, ys, xs, sizes):
    """Known pixels in each block's window (the block at (ys, xs), `sizes` wide, grown by
    `border`; outside the array counts 0), from the hole's _table: the window's pixels
    inside the array less its hole pixels."""
    holes, inside = _box_sums(
        hole_sat, ys - border, ys + sizes + border, xs - border, xs + sizes + border
    )
    return inside - holes


def _hole_cells(hole: np.ndarray, origin, cells_shape, cell: int) -> np.ndarray:
    """Whether each cell (a smallest block) of the grid holds a hole pixel; the grid starts at
    `origin` in the crop (rows and columns before the crop hold none)."""
    oy, ox = origin
    ncy, ncx = cells_shape
    grid = np.zeros((ncy * cell, ncx * cell), bool)
    ya, xa = max(0, -oy), max(0, -ox)  # grid rows and columns above / left of the image
    part = hole[oy + ya : oy + ncy * cell, ox + xa : ox + ncx * cell]
    grid[ya : ya + part.shape[0], xa : xa + part.shape[1]] = part
    return grid.reshape(ncy, cell, ncx, cell).any((1, 3))


def _block_sizes(cells, hole_sat, origin, tops, top: int, cell: int, border: int, split: float):
    """(cell rows, cell columns, sizes in cells) of the blocks holding hole cells: the
    grid's `tops` top blocks (`top` cells wide), each cut in four while its window holds
    less than `split` of known pixels (down to one cell); the blocks of each size in turn,
    each size's in the order of their parents."""
    oy, ox = origin
    cells_sat = _table(cells)
    a, b = (g.ravel() * top for g in np.indices(tops))
    s = np.full(a.size, top, np.int64)
    found = []
    while a.size:
        has = _box_sums(cells_sat, a, a + s, b, b + s)[0] > 0
        area = (s * cell + 2 * border) ** 2
        known = _known_sums(hole_sat, border, oy + a * cell, ox + b * cell, s * cell)
        # the share as a float64, as the float table of the known pixels gave it (exact)
        cut = has & (known.astype(np.float64) / area < split) & (s > 1)
        keep = has & ~cut
        found.append((a[keep], b[keep], s[keep]))
        h = s[cut] // 2
        # each cut block's four quarters, in the order (0, 0), (0, h), (h, 0), (h, h)
        a = (a[cut][:, None] + h[:, None] * np.array([0, 0, 1, 1])).ravel()
        b = (b[cut][:, None] + h[:, None] * np.array([0, 1, 0, 1])).ravel()
        s = np.repeat(h, 4)
    return tuple(np.concatenate([f[k] for f in found]).astype(np.int64) for k in range(3))


def _neighbours(found, reach: int, chunk: int = 1024):
    """(pi, pj): the pairs of blocks where j's cells lie in i's window (and i's in j's: the
    relation is symmetric); `found` holds (cell rows, cell columns, sizes in cells) of the
    blocks, `reach` is how many cells a window reaches beyond its block. Blocks are compared
    `chunk` at a time against all, so that memory stays chunk x blocks."""
    a, b, s = found
    pi, pj = [], []
    for c0 in range(0, len(a), chunk):
        i = slice(c0, c0 + chunk)
        near = (
            (a[None, :] < (a[i] + s[i] + reach)[:, None])
            & ((a[i] - reach)[:, None] < (a + s)[None, :])
            & (b[None, :] < (b[i] + s[i] + reach)[:, None])
            & ((b[i] - reach)[:, None] < (b + s)[None, :])
        )
        ii, jj = np.nonzero(near)
        ii += c0
        keep = ii != jj
        pi.append(ii[keep])
        pj.append(jj[keep])
    return np.concatenate(pi).astype(np.int64), np.concatenate(pj).astype(np.int64)


def _waves(hole_sat, pixels, pairs, border: int, delta: float):
    """(order, waves, block_wave): the blocks wave by wave, (first, count) of each wave in
    `order`, and each block's wave. `pixels` is (rows, columns, sizes) of the blocks in the
    crop, `hole_sat` the crop's hole's _table; `pairs` their neighbours. Neighbours never
    share a wave, and a filled block adds its hole pixels in a neighbour's window, times
    delta, to that neighbour's score."""
    py, px, ps = pixels
    pi, pj = pairs
    n = len(py)
    known_n = _known_sums(hole_sat, border, py, px, ps)
    # hole pixels of j inside i's window: they count delta once j is filled
    overlap = _box_sums(
        hole_sat,
        np.maximum(py[pj], py[pi] - border),
        np.minimum(py[pj] + ps[pj], py[pi] + ps[pi] + border),
        np.maximum(px[pj], px[pi] - border),
        np.minimum(px[pj] + ps[pj], px[pi] + ps[pi] + border),
    )[0]
    area = (ps + 2 * border) ** 2
    filled_n = np.zeros(n, np.int64)
    block_wave = np.full(n, -1, np.int64)
    pending = np.ones(n, bool)
    rank = np.full(n, -1, np.int64)
    order, waves, first = [], [], 0
    while pending.any():
        idx = np.flatnonzero(pending)
        score = (known_n[idx] + delta * filled_n[idx]) / area[idx]
        # unique ranks: the larger score first, then the lower index
        rank[idx[np.lexsort((-idx, score))]] = np.arange(idx.size)
        live = pending[pi] & pending[pj]
        pi, pj, overlap = pi[live], pj[live], overlap[live]
        # a block comes first unless a pending neighbour outranks it
        outranked = np.zeros(n, bool)
        outranked[pi[rank[pj] > rank[pi]]] = True
        ok = (score > 0) | (score.max() <= 0)
        chosen = idx[~outranked[idx] & ok]
        block_wave[chosen] = len(waves)
        waves.append((first, chosen.size))
        order.append(chosen)
        first += chosen.size
        pending[chosen] = False
        done = ~pending[pj]
        # (exact: whole numbers summed in float64)
        filled_n += np.bincount(pi[done], overlap[done], n).astype(np.int64)
    return np.concatenate(order), waves, block_wave


def plan(
    omega: np.ndarray,
    *,
    block: int = 8,
    min_block: int = 4,
    border: int = 12,
    split: float = 0.3,
    delta: float = 1.0,
    shift: tuple = (0, 0),
):
    """The blocks and their waves for a mask.

    Parameters
    ----------
    omega : np.ndarray
        bool (rows, cols), True where to fill.
    block, min_block, border, split, delta : int, int, int, float, float
        As for `clpde.inpainting.spectral.fill`.
    shift : tuple
        (rows, columns) by which the block grid starts before the damage's bounding box.

    Returns
    -------
    crop : tuple
        (y0, y1, x0, x1), the part of the image that the windows reach.
    blocks : np.ndarray
        int32 (n, 4): row, column (in the crop; < 0 where a block starts before the image),
        size B, window L of each block, wave by wave.
    waves : list
        (first, count) of each wave in `blocks`.
    wave_of : np.ndarray
        int32 over the crop: -1 for known pixels, else the wave that fills the pixel.
    """
    ny, nx = omega.shape
    rows, cols = np.flatnonzero(omega.any(1)), np.flatnonzero(omega.any(0))
    if rows.size == 0:
        return (0, 0, 0, 0), np.zeros((0, 4), np.int32), [], np.zeros((0, 0), np.int32)
    gy0, gx0 = rows[0] - shift[0], cols[0] - shift[1]  # the block grid's origin (may be < 0)
    gy = -(-(rows[-1] + 1 - gy0) // block)
    gx = -(-(cols[-1] + 1 - gx0) // block)
    cy0, cx0 = max(0, gy0 - border), max(0, gx0 - border)
    cy1 = min(ny, gy0 + gy * block + border)
    cx1 = min(nx, gx0 + gx * block + border)
    hole = omega[cy0:cy1, cx0:cx1]
    oy, ox = gy0 - cy0, gx0 - cx0  # the block grid's origin in the crop
    # the hole on the grid of the smallest blocks (cells), padded to whole top blocks
    cell, top = min_block, block // min_block
    ncy, ncx = gy * top, gx * top
    cells = _hole_cells(hole, (oy, ox), (ncy, ncx), cell)
    hole_sat = _table(hole)
    found = _block_sizes(cells, hole_sat, (oy, ox), (gy, gx), top, cell, border, split)
    fy, fx, fs = found
    label = np.full((ncy, ncx), -1, np.int64)  # which block owns each cell
    for size in np.unique(fs):  # blocks never overlap: each size's cells at once
        i = np.flatnonzero(fs == size)
        for dy in range(size):
            for dx in range(size):
                label[fy[i] + dy, fx[i] + dx] = i
    reach = -(-border // cell)  # cells a window reaches beyond its block
    py, px, ps = oy + fy * cell, ox + fx * cell, fs * cell
    pairs = _neighbours(found, reach)
    order, waves, block_wave = _waves(hole_sat, (py, px, ps), pairs, border, delta)
    blocks = np.stack([py[order], px[order], ps[order], ps[order] + 2 * border], 1)
    wave_of = np.full(hole.shape, -1, np.int32)
    hy, hx = np.nonzero(hole)
    wave_of[hy, hx] = block_wave[label[(hy - oy) // cell, (hx - ox) // cell]]
    return (cy0, cy1, cx0, cx1), blocks.astype(np.int32), waves, wave_of


def launch_table(plans, omega, origin, shape, picking):
    """(wave_of, blocks, starts) for the launches: each copy's waves over the union crop
    (at `origin`, of `shape`), and the blocks of every copy, wave by wave, as rows of
    (row, column, size, window, copy, picks, minor picks); wave w's blocks are
    blocks[starts[w]: starts[w + 1]]. `picking` is (iterations, per_pixel, minor)."""
    iterations, per_pixel, minor = picking
    y0, x0 = origin
    wave_of = np.full((len(plans),) + tuple(shape), -1, np.int32)
    rows, wave_ids = [], []
    for c, ((cy0, cy1, cx0, cx1), blocks, waves, w_of) in enumerate(plans):
        wave_of[c, cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0] = w_of
        moved = blocks + np.array([cy0 - y0, cx0 - x0, 0, 0], np.int32)
        picks = block_iterations(blocks, omega[cy0:cy1, cx0:cx1], iterations, per_pixel)
        minor_picks = minor_iterations(picks, minor)
        copy = np.full((len(blocks), 1), c, np.int32)
        rows.append(np.concatenate([moved, copy, picks[:, None], minor_picks[:, None]], 1))
        wave_ids.append(np.repeat(np.arange(len(waves)), [count for _, count in waves]))
    # wave by wave, each wave's blocks copy by copy (a stable sort keeps the copies' order)
    wave_ids = np.concatenate(wave_ids)
    by_wave = np.argsort(wave_ids, kind="stable")
    all_blocks = np.ascontiguousarray(np.concatenate(rows)[by_wave], np.int32)
    starts = np.concatenate([[0], np.cumsum(np.bincount(wave_ids))]).astype(np.int64)
    return wave_of, all_blocks, starts


def block_iterations(blocks, hole, iterations: int, per_pixel: float) -> np.ndarray:
    """Each block's most picks: `iterations`, or with per_pixel > 0, per_pixel picks for each
    of its hole pixels (at least 4), whichever is fewer: a speck needs fewer terms than a
    block-wide hole."""
    if per_pixel <= 0:
        return np.full(len(blocks), iterations, np.int32)
    y, x, s = (blocks[:, k].astype(np.int64) for k in range(3))
    holes = _box_sums(_table(hole), y, y + s, x, x + s)[0]
    return np.minimum(iterations, np.maximum(4, np.ceil(per_pixel * holes))).astype(np.int32)


def shifts_of(shifts: int, block: int) -> list:
    """The block grids' offsets: 1, 2 (a half block diagonally) or 4 (every half block)."""
    h = block // 2
    return {1: [(0, 0)], 2: [(0, 0), (h, h)], 4: [(0, 0), (0, h), (h, 0), (h, h)]}[shifts]


def minor_iterations(picks: np.ndarray, minor: float) -> np.ndarray:
    """Each block's most picks in the channels after the first: `minor` of its picks (at
    least 1). In the principal-axis colour basis those channels hold the colours' smaller
    variances, which fewer terms model as well."""
    return np.maximum(1, np.rint(minor * picks)).astype(np.int32)
