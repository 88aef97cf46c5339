"""The biharmonic fill of a box's hole: L(L u) = 0 at the hole's voxels, L the seven-point
Laplacian with the voxel spacing and Neumann borders at the box's faces, the known voxels
(two rings of them around the hole, as the box is grown by two) its boundary data.

The equations restricted to the hole are A e = -(L L u0) there, A = (L L) on the hole's
voxels: A = B^T B with B = L's columns on the hole, symmetric and positive definite while
a voxel of the box is known. Conjugate gradients solve it on the device, from u0 the
harmonic fill of the same box (clpde/volumes/inpaint.py), which already holds the hole's
coarse shape, so that only the correction towards the smoother fill is left. A box is
solved by one work-group in one launch (kernels/volumes/volume.cl, volume_biharmonic_cg):
the boxes are small, and a launch and a read-back per CG step cost more than the step.
"""

from __future__ import annotations

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from .grid import VolumeGrid

KERNEL_FILES = ("volumes/volume.cl",)

GROUP = 128  # work-items of the one work-group that solves a box (a power of two)


def biharmonic_cg(
    grid: VolumeGrid, u: np.ndarray, hole: np.ndarray, max_iterations: int, rtol: float
):
    """u (nc, nz, ny, nx) with its hole's voxels replaced by the discrete biharmonic fill,
    by conjugate gradients from u itself (each channel on its own); u is not modified.

    Stops when the residual's norm fell by rtol, or after max_iterations (or the hole's
    voxel count, where exact arithmetic would have ended)."""
    rt = grid.runtime
    q = rt.queue
    solve = rt.kernel("volumes/volume.cl", "volume_biharmonic_cg", grid.dtype)
    nz, ny, nx = hole.shape
    mask = cla.to_device(q, hole.astype(np.uint8).reshape(-1))
    scratch = [cla.empty(q, hole.size, grid.dtype) for _ in range(4)]
    steps = cla.empty(q, 1, np.int32)
    cap = min(int(max_iterations), int(hole.sum()))
    out = np.array(u, dtype=np.float64)
    for c in range(u.shape[0]):
        x = cla.to_device(q, u[c].astype(grid.dtype).reshape(-1))
        solve(
            q, (GROUP,), (GROUP,), x.data, *(s.data for s in scratch), mask.data,
            cl.LocalMemory(GROUP * grid.dtype.itemsize), steps.data, np.int32(cap),
            grid.scalar(rtol**2), *grid.inverse2, *(np.int32(v) for v in (nx, ny, nz)),
        )  # fmt: skip
        out[c][hole] = x.get().reshape(hole.shape)[hole]
    return out
