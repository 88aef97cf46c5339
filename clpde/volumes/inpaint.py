"""Inpainting of 3D volumes: the masked voxels are filled by the solution of Laplace's
equation (seven points, with voxel spacing) whose boundary values are the known voxels
around them, by red-black SOR (kernels/volumes/volume.cl), by the biharmonic equation's,
L(L u) = 0, by conjugate gradients from that harmonic fill (clpde/volumes/biharmonic.py),
or by sparsity in 4^3 DCT blocks from that harmonic fill (clpde/volumes/spectral.py).

Memory and time follow the damage: each connected component of the mask is solved in its own
box (its bounding box grown by one voxel), and each box starts from the solution of the same
problem on a grid twice as coarse (recursively), so that SOR only has to remove the fine
error instead of carrying the boundary values across the whole hole.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from .._progress import Progress, check_progress, progress_bar
from ..errors import InputError
from ..imagedata import compute_dtype, positive
from ..runtime import get_runtime
from .biharmonic import biharmonic_cg
from .grid import VolumeGrid, check_spacing, to_volume_layout
from .spectral import BLOCK, spectral_fill, thresholds

KERNEL_FILES = ("volumes/volume.cl",)

CHECK_EVERY = 10  # sweeps between convergence tests
COARSEST = 4  # boxes with a side of fewer voxels are solved without a coarser start
METHODS = ("harmonic", "biharmonic", "spectral")
# voxels of known data each method's box keeps around a component: the biharmonic stencil
# reaches two, the spectral fill's 4^3 blocks three
RING = {"harmonic": 1, "biharmonic": 2, "spectral": BLOCK - 1}
# the biharmonic CG stops when its residual fell by CG_TOL tol (1e-3 at the default tol:
# chosen on the calibration half, where 1e-4 gave the same PSNR to 0.01 dB in twice the steps)
CG_TOL = 10.0
# ... from a harmonic start whose SOR stops at 0.1 per sweep (ten sweeps per level, on top of
# the coarse grids' start): on the calibration half the same PSNR as a start at tol 1e-4,
# to 0.01 dB, in about half the time
START_TOL = 0.1


def inpaint_volume(
    volume,
    mask,
    channel_axis: int | None = None,
    *,
    method: str = "biharmonic",
    spacing=None,
    device=None,
    tol: float = 1e-4,
    max_sweeps: int = 5000,
    dtype=None,
    progress: Progress = None,
) -> np.ndarray:
    """Fill the masked voxels of a (Z, Y, X) or (Z, Y, X, C) volume with the harmonic
    (smoothest membrane) or biharmonic (thin plate) interpolation of the voxels around them.

    Parameters
    ----------
    volume : (Z, Y, X) or (Z, Y, X, C) array
        Integer or float voxels, never modified; the masked ones are ignored (but must be
        finite).
    mask : (Z, Y, X) array of bool
        True where the voxels are missing.
    channel_axis : int, optional
        The axis of the channels, each filled on its own.
    method : {'biharmonic', 'harmonic', 'spectral'}, optional
        The biharmonic equation (the default: continues the gradients across the hole too,
        from two rings of known voxels; solved from a harmonic start), Laplace's (the
        membrane; obeys the maximum principle, no overshoot), or the spectral model (the
        volume sparse in every 4 x 4 x 4 block's DCT, by iterative hard thresholding from
        a harmonic start; 3 rings; blocks in voxels, the spacing only in the start).
    spacing : (3,) array_like, optional
        The voxel size (z, y, x); thick slices weigh their neighbours less.
    device : str or int, optional
        An OpenCL device ('cpu', 'gpu', an index or a name part; see `clpde.devices`).
    tol : float, optional
        Stop a box when no voxel changed by more than tol (on [0, 1] data) per sweep over
        the last sweeps; the biharmonic's conjugate gradients when their residual fell by
        10 tol.
    max_sweeps : int, optional
        The cap on SOR sweeps per box and level, and on the biharmonic's conjugate-gradient
        iterations per box and channel.
    dtype : {float32, float64}, optional
        The device's arithmetic.
    progress : bool or callable, optional
        Draw a progress bar over the missing voxels, filled box by box; by default only
        for long runs on a terminal. A callable ``progress(done, total)`` hears the voxels
        filled so far and in all after each box (and may stop the fill by raising).

    Returns
    -------
    ndarray
        The filled volume, the input's shape and dtype; voxels outside the mask unchanged.

    Raises
    ------
    InputError
        For a mask of another shape, a mask that covers the whole volume, bad spacing or an
        unknown method.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.volumes import inpaint_volume
    >>> z, y, x = np.indices((8, 9, 10), dtype=float)
    >>> ramp = 0.5 * x + 0.25 * z
    >>> mask = np.zeros(ramp.shape, bool)
    >>> mask[3:5, 3:6, 4:7] = True
    >>> bool(np.abs(inpaint_volume(ramp, mask) - ramp).max() < 1e-3)
    True
    """
    if method not in METHODS:
        raise InputError(f"method must be one of {', '.join(METHODS)}, not {method!r}")
    h = check_spacing(spacing)
    data, layout = to_volume_layout(volume, channel_axis, spacing)
    hole = np.asarray(mask)
    if hole.shape != data.shape[1:]:
        raise InputError(
            f"mask has shape {hole.shape}; it must be the volume's (Z, Y, X) shape {data.shape[1:]}"
        )
    hole = hole.astype(bool)
    if hole.all():
        raise InputError("mask covers the whole volume: nothing to fill it from")
    tol = positive("tol", tol)
    check_progress(progress)
    grid_of = _GridMaker(get_runtime(device), compute_dtype(None, dtype))
    labels, count = ndimage.label(hole)
    ring = RING[method]
    desc = f"clpde inpaint {method} (volume)"
    with progress_bar(progress, int(hole.sum()), desc, unit="voxel") as bar:
        for k, box in enumerate(ndimage.find_objects(labels), start=1):
            grown = tuple(
                slice(max(0, s.start - ring), min(n, s.stop + ring))
                for s, n in zip(box, hole.shape, strict=True)
            )
            mine = labels[grown] == k
            u = data[(slice(None),) + grown]
            filled = _fill_box(grid_of, method, u.copy(), hole[grown], h, tol, int(max_sweeps))
            u[:, mine] = filled[:, mine]
            bar.update(int(mine.sum()))
    # the known voxels exactly as given (the [0, 1] round trip of floats may round them)
    where = hole if layout.channel_axis is None else np.expand_dims(hole, layout.channel_axis)
    return np.where(where, layout.restore(data), np.asarray(volume))


def _fill_box(grid_of, method, u, hole, h, tol, max_sweeps) -> np.ndarray:
    """u (nc, nz, ny, nx), a box, with its hole's voxels filled by `method`; every masked
    voxel of the box (another component's too, reaching in) is an unknown."""
    # the biharmonic's and spectral's start needs only the harmonic fill's shape
    start_tol = tol if method == "harmonic" else max(START_TOL, tol)
    filled = _solve(grid_of, u, hole, h, start_tol, max_sweeps)
    if method == "biharmonic":
        filled = biharmonic_cg(grid_of(u.shape, h), filled, hole, max_sweeps, CG_TOL * tol)
    elif method == "spectral":
        filled = spectral_fill(grid_of(u.shape, h), filled, hole, thresholds())
    return filled


class _GridMaker:
    def __init__(self, runtime, dtype):
        self.runtime, self.dtype = runtime, dtype

    def __call__(self, shape, h) -> VolumeGrid:
        return VolumeGrid(self.runtime, shape, self.dtype, h)


def _solve(grid_of, u: np.ndarray, hole: np.ndarray, h, tol, max_sweeps) -> np.ndarray:
    """u (nc, nz, ny, nx) with its hole voxels filled: a coarse start, then SOR."""
    if min(hole.shape) >= 2 * COARSEST and hole.sum() > 64:
        coarse_u, coarse_hole = _restrict(u, hole)
        coarse = _solve(grid_of, coarse_u, coarse_hole, 2 * np.asarray(h), tol, max_sweeps)
        start = np.repeat(np.repeat(np.repeat(coarse, 2, 1), 2, 2), 2, 3)
        start = start[:, : hole.shape[0], : hole.shape[1], : hole.shape[2]]
        u[:, hole] = start[:, hole]
    else:
        # no coarser start: the mean of the known voxels (the box's border)
        u[:, hole] = u[:, ~hole].mean(axis=1)[:, None]
    return sor(grid_of(u.shape, np.asarray(h)), u, hole, tol, max_sweeps)


def _restrict(u: np.ndarray, hole: np.ndarray):
    """The box on a grid twice as coarse: a coarse voxel is known where its (up to) eight
    fine voxels are all known, with their mean."""
    nc = u.shape[0]
    pad = [(0, n % 2) for n in hole.shape]
    hp = np.pad(hole, pad, mode="edge")
    up = np.pad(u, [(0, 0)] + pad, mode="edge")
    cz, cy, cx = (n // 2 for n in hp.shape)
    blocks = up.reshape(nc, cz, 2, cy, 2, cx, 2)
    coarse = blocks.mean(axis=(2, 4, 6))
    coarse_hole = hp.reshape(cz, 2, cy, 2, cx, 2).any(axis=(1, 3, 5))
    if coarse_hole.all():  # keep a known rim: the hole's border is what it is filled from
        coarse_hole[[0, -1], :, :] = coarse_hole[:, [0, -1], :] = False
        coarse_hole[:, :, [0, -1]] = False
    return coarse, coarse_hole


def sor(grid: VolumeGrid, u: np.ndarray, hole: np.ndarray, tol, max_sweeps) -> np.ndarray:
    """Red-black SOR sweeps of Lap u = 0 over `hole` until no voxel moves by more than tol
    per sweep (tested every CHECK_EVERY sweeps) or max_sweeps; u is not modified."""
    rt, q = grid.runtime, grid.runtime.queue
    sweep = rt.kernel("volumes/volume.cl", "volume_harmonic_sweep", grid.dtype)
    nz, ny, nx = hole.shape
    # the classical optimum for the model problem across the hole's largest extent
    extent = max(nz, ny, nx)
    omega = grid.scalar(2.0 / (1.0 + np.sin(np.pi / extent)))
    dev = cla.to_device(q, u.astype(grid.dtype).reshape(-1))
    mask = cla.to_device(q, hole.astype(np.uint8).reshape(-1))
    before = u[:, hole].astype(grid.dtype)
    done = 0
    while done < max_sweeps:
        for _ in range(min(CHECK_EVERY, max_sweeps - done)):
            for colour in (0, 1):
                grid.launch(sweep, dev.data, mask.data, np.int32(colour), omega, *grid.inverse2)
            done += 1
        now = dev.get().reshape(u.shape)[:, hole]
        if np.abs(now - before).max() < tol * CHECK_EVERY:
            break
        before = now
    return dev.get().reshape(u.shape).astype(np.float64)
