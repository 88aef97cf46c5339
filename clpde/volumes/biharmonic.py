"""The biharmonic fill of a box's hole: L(L u) = 0 at the hole's voxels, L the seven-point
Laplacian with the voxel spacing and Neumann borders at the box's faces, the known voxels
(two rings of them around the hole, as the box is grown by two) its boundary data.

The equations restricted to the hole are A e = -(L L u0) there, A = (L L) on the hole's
voxels: A = B^T B with B = L's columns on the hole, symmetric and positive definite while
a voxel of the box is known. Conjugate gradients solve it on the device, from u0 the
harmonic fill of the same box (clpde/volumes/inpaint.py), which already holds the hole's
coarse shape, so that only the correction towards the smoother fill is left.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .grid import VolumeGrid

RTOL = 1e-3  # stop when the residual's norm fell by this factor (chosen on the calibration half)


def biharmonic_cg(
    grid: VolumeGrid, u: np.ndarray, hole: np.ndarray, max_iterations: int, rtol: float = RTOL
):
    """u (nc, nz, ny, nx) with its hole's voxels replaced by the discrete biharmonic fill,
    by conjugate gradients from u itself (each channel on its own); u is not modified.

    Stops when the residual's norm fell by rtol, or after max_iterations (or the hole's
    voxel count, where exact arithmetic would have ended)."""
    rt = grid.runtime
    q = rt.queue
    kernel = {
        name: rt.kernel("volumes/volume.cl", name, grid.dtype)
        for name in ("volume_laplacian", "volume_cg_dot", "volume_cg_step", "volume_cg_direction")
    }  # fmt: skip
    one = VolumeGrid(rt, (1,) + hole.shape, grid.dtype, grid.spacing)
    nz, ny, _ = hole.shape
    local = (1, 1, 1) if rt.is_cpu else None
    mask = cla.to_device(q, hole.astype(np.uint8).reshape(-1))
    partial = cla.empty(q, nz * ny, grid.dtype)
    out = np.array(u, dtype=np.float64)
    cap = min(int(max_iterations), int(hole.sum()))

    def apply(src, tmp, dst):
        """dst = A src (src zero off the hole): L, then L kept on the hole."""
        lap = kernel["volume_laplacian"]
        one.launch(lap, src.data, tmp.data, mask.data, np.int32(0), *one.inverse2)
        one.launch(lap, tmp.data, dst.data, mask.data, np.int32(1), *one.inverse2)

    def rows(name, *args) -> float:
        """A per-row kernel's partial sums, added up."""
        kernel[name](q, (1, ny, nz), local, *args, partial.data, *one.sizes(1))
        return float(partial.get().astype(np.float64).sum())

    for c in range(u.shape[0]):
        x = cla.to_device(q, u[c].astype(grid.dtype).reshape(-1))
        tmp, ap = cla.empty(q, hole.size, grid.dtype), cla.empty(q, hole.size, grid.dtype)
        p, r = (cla.to_device(q, np.zeros(hole.size, grid.dtype)) for _ in range(2))
        apply(x, tmp, ap)
        # r = 0 - 1 ap = -A u0 on the hole, the correction's right-hand side (tmp is scratch)
        rr = rows("volume_cg_step", tmp.data, r.data, p.data, ap.data, grid.scalar(1.0))
        stop = (rtol**2) * rr
        beta = 0.0
        for _ in range(cap):
            if rr <= stop or rr == 0:
                break
            one.launch(kernel["volume_cg_direction"], r.data, p.data, grid.scalar(beta))
            apply(p, tmp, ap)
            alpha = rr / rows("volume_cg_dot", p.data, ap.data)
            rr_new = rows("volume_cg_step", x.data, r.data, p.data, ap.data, grid.scalar(alpha))
            beta, rr = rr_new / rr, rr_new
        out[c][hole] = x.get().reshape(hole.shape)[hole]
    return out
