"""The spectral fill of a box's hole: the volume is modelled as sparse in 4 x 4 x 4 blocks of
the DCT, every block position (all shifts) at once, and the hole's voxels are found by
iterative hard thresholding (Guleryuz, IEEE TIP 2006, in 3D): each pass takes every block
that holds a hole voxel to its DCT, zeroes the coefficients below a threshold (keeping the
mean), takes it back, and sets each hole voxel to the mean of its blocks' values; the
threshold falls geometrically from FIRST to LAST over ITERATIONS passes, so that the coarse
structure settles before the fine. The known voxels never change.

It starts from the harmonic fill of the same box (clpde/volumes/inpaint.py). The blocks are
in voxels, so the model does not use the spacing (the start does). Each pass is two launches
(kernels/volumes/volume.cl: volume_threshold_blocks, one work-item per block, and
volume_average_blocks, one per hole voxel), with nothing read back until the end.

Block side, passes and thresholds (on [0, 1] data) were chosen on the calibration half of
benchmarks/volumes.py (nibabel's example4d; PSNR in the hole): blocks of 4 at every shift
29.16 dB, at every other voxel 28.88, blocks of 8 at every fourth 28.34; 10 passes 28.85;
a last threshold of 0.01 29.10, of 0.03 29.17; a first of 0.1 28.94.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .grid import VolumeGrid

KERNEL_FILES = ("volumes/volume.cl",)

BLOCK = 4  # kernels/volumes/volume.cl's blocks are 4 x 4 x 4
ITERATIONS = 20
FIRST = 0.3
LAST = 0.02


def thresholds(iterations: int = ITERATIONS, first: float = FIRST, last: float = LAST):
    """The threshold of each pass: geometric from `first` to `last`."""
    steps = np.arange(iterations) / max(1, iterations - 1)
    return first * (last / first) ** steps


def block_corners(hole: np.ndarray) -> np.ndarray:
    """(z, y, x) of every BLOCK^3 block inside the box that holds a hole voxel, in C order."""
    nz, ny, nx = hole.shape
    if min(hole.shape) < BLOCK:
        return np.zeros((0, 3), np.int64)
    # hole voxels per block from the 3D cumulative sum (a summed-volume table)
    table = np.pad(hole.astype(np.int64), ((1, 0), (1, 0), (1, 0)))
    for axis in range(3):
        table = np.cumsum(table, axis=axis)
    b = BLOCK
    count = np.zeros((nz - b + 1, ny - b + 1, nx - b + 1), np.int64)
    for dz, dy, dx in np.ndindex(2, 2, 2):
        sign = (-1) ** (3 - dz - dy - dx)
        count += (
            sign
            * table[
                dz * b : dz * b + nz - b + 1,
                dy * b : dy * b + ny - b + 1,
                dx * b : dx * b + nx - b + 1,
            ]
        )
    return np.argwhere(count > 0)


def spectral_fill(grid: VolumeGrid, u: np.ndarray, hole: np.ndarray, levels) -> np.ndarray:
    """u (nc, nz, ny, nx) with its hole's voxels replaced by the thresholding passes' result
    (one pass per threshold in `levels`, each channel on its own); u is not modified.

    A hole voxel no block holds (a box thinner than a block) keeps its start."""
    rt = grid.runtime
    q = rt.queue
    threshold = rt.kernel("volumes/volume.cl", "volume_threshold_blocks", grid.dtype)
    average = rt.kernel("volumes/volume.cl", "volume_average_blocks", grid.dtype)
    nz, ny, nx = hole.shape
    corners = block_corners(hole)
    out = np.array(u, dtype=np.float64)
    if len(corners) == 0:
        return out
    first = (corners[:, 0] * ny + corners[:, 1]) * nx + corners[:, 2]
    block_of = np.full(hole.size, -1, np.int32)
    block_of[first] = np.arange(len(first), dtype=np.int32)
    voxels = np.flatnonzero(hole).astype(np.int32)
    rt.check_alloc(64 * len(first) * grid.dtype.itemsize, "spectral fill's block values")
    blocks, count = np.int32(len(first)), np.int32(len(voxels))
    corner_dev = cla.to_device(q, first.astype(np.int32))
    block_dev = cla.to_device(q, block_of)
    voxel_dev = cla.to_device(q, voxels)
    values = cla.empty(q, 64 * len(first), grid.dtype)
    wg = 64
    size_b, size_v = -(-len(first) // wg) * wg, -(-len(voxels) // wg) * wg
    for c in range(u.shape[0]):
        x = cla.to_device(q, u[c].astype(grid.dtype).reshape(-1))
        for level in levels:
            threshold(
                q, (size_b,), (wg,), x.data, corner_dev.data, blocks, grid.scalar(level),
                values.data, np.int32(nx), np.int32(ny),
            )  # fmt: skip
            average(
                q, (size_v,), (wg,), x.data, voxel_dev.data, count, block_dev.data,
                values.data, np.int32(nx), np.int32(ny),
            )  # fmt: skip
        out[c][hole] = x.get().reshape(hole.shape)[hole]
    return out
