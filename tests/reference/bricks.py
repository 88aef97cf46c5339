"""NumPy references of the brick storage (clpde/bricks.py, kernels/surface/bricks.cl).

Written brick by brick with plain loops, independently of bricks.py's vectorised build: the
layout (bricks 1..n in Morton order, brick 0 the sentinel, x fastest inside a brick, rows
lengthened along each axis by an apron of the next brick places' first cells), the
27-neighbour table, and the kernels as the dense references of tests/reference/surface.py
read through it.
"""

import numpy as np


def morton(bx, by, bz):
    key = 0
    for bit in range(21):
        key |= ((bx >> bit) & 1) << (3 * bit)
        key |= ((by >> bit) & 1) << (3 * bit + 1)
        key |= ((bz >> bit) & 1) << (3 * bit + 2)
    return key


def brick_coords(stored, brick):
    """Brick coordinates (x, y, z) of every brick holding a stored cell, in Morton order."""
    bx, by, bz = brick
    found = {(x // bx, y // by, z // bz) for z, y, x in zip(*np.nonzero(stored), strict=False)}
    return sorted(found, key=lambda c: morton(*c))


def neighbours(coords):
    """(n + 2, 27) table: entry (dz + 1) 9 + (dy + 1) 3 + dx + 1 of brick i + 1 is the index
    of the brick at offset (dx, dy, dz), 0 where none is stored."""
    index = {c: i + 1 for i, c in enumerate(coords)}
    table = np.zeros((len(coords) + 2, 27), np.int32)
    for i, (x, y, z) in enumerate(coords):
        for dz in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    table[i + 1, (dz + 1) * 9 + (dy + 1) * 3 + dx + 1] = index.get(
                        (x + dx, y + dy, z + dz), 0
                    )
    return table


def to_bricks(padded, coords, brick, apron=0):
    """(nc, n + 2, BZ + apron, BY + apron, BX + apron) brick values of padded (nc, PZ, PY, PX)
    volumes (the apron: the next brick places' first cells)."""
    bx, by, bz = brick
    nc, pz, py, px = padded.shape
    out = np.zeros((nc, len(coords) + 2, bz + apron, by + apron, bx + apron))
    for i, (cx, cy, cz) in enumerate(coords):
        for z in range(bz + apron):
            for y in range(by + apron):
                for x in range(bx + apron):
                    gz, gy, gx = cz * bz + z, cy * by + y, cx * bx + x
                    if gz < pz and gy < py and gx < px:
                        out[:, i + 1, z, y, x] = padded[:, gz, gy, gx]
    return out


def brick_index(cells, padded_shape, coords, brick, apron=0):
    """Brick-storage indices of flat padded cells (0..: brick 0 the sentinel)."""
    bx, by, bz = brick
    _, py, px = padded_shape
    index = {c: i + 1 for i, c in enumerate(coords)}
    out = []
    for cell in cells:
        z, rem = divmod(int(cell), py * px)
        y, x = divmod(rem, px)
        b = index.get((x // bx, y // by, z // bz), 0)
        out.append(((b * (bz + apron) + z % bz) * (by + apron) + y % by) * (bx + apron) + x % bx)
    return np.array(out)


def to_tiles(padded, coords, brick, halo):
    """(nc, n + 2, BZ + 2 halo, BY + 2 halo, BX + 2 halo): each brick with the cells within
    `halo` of its faces (0 outside the grid)."""
    bx, by, bz = brick
    nc, pz, py, px = padded.shape
    h2 = 2 * halo
    out = np.zeros((nc, len(coords) + 2, bz + h2, by + h2, bx + h2))
    for i, (cx, cy, cz) in enumerate(coords):
        for z in range(bz + h2):
            for y in range(by + h2):
                for x in range(bx + h2):
                    gz, gy, gx = cz * bz + z - halo, cy * by + y - halo, cx * bx + x - halo
                    if 0 <= gz < pz and 0 <= gy < py and 0 <= gx < px:
                        out[:, i + 1, z, y, x] = padded[:, gz, gy, gx]
    return out
