"""Total-variation (ROF) denoising of 3D volumes: min_u TV(u) + lambda/2 |u - u0|^2 with
TV(u) = sum over voxels of |grad u|, grad the forward difference over the voxel spacing, so a
thick slice's difference counts for its physical gradient. Solved in the dual by fast
projected gradient (kernels/volumes/volume.cl, as kernels/planar/rof.cl does in 2D), with
lambda fitted on the host to the noise level when sigma is given or estimated."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .._progress import progress_bar
from ..errors import InputError
from ..imagedata import check_steps, compute_dtype, positive
from ..runtime import get_runtime
from .grid import VolumeGrid, check_spacing, to_volume_layout

KERNEL_FILES = ("volumes/volume.cl",)

# The difference of two discrete Laplacians (Immerkaer 1996), applied in each slice: it turns
# white noise of deviation sigma into values of deviation 6 sigma.
_NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
_MAD_TO_STD = 1.0 / 0.6744897501960817
_LAMBDA_MIN = 1e-6


def estimate_sigma_volume(data: np.ndarray) -> float:
    """Noise deviation of one (nz, ny, nx) channel: the median absolute value of the in-slice
    Laplacian-difference residual of every slice, as for a normal variable (the 2D rule of
    clpde.planar.rof.estimate_sigma, over all slices at once)."""
    nz, ny, nx = data.shape
    if ny < 3 or nx < 3:
        raise InputError(
            f"slices of {nx}x{ny} voxels are too small to estimate the noise from; give "
            "sigma or weight"
        )
    r = sum(
        _NOISE_MASK[i, j] * data[:, i : ny - 2 + i, j : nx - 2 + j]
        for i in range(3)
        for j in range(3)
    )
    return float(np.median(np.abs(r))) * _MAD_TO_STD / 6.0


def denoise_tv_volume(
    volume,
    sigma: float | None = None,
    weight: float | None = None,
    channel_axis: int | None = None,
    *,
    spacing=None,
    device=None,
    max_steps: int | None = None,
    tol: float | None = None,
    check_every: int | None = None,
    progress: bool | None = None,
    dtype=None,
    vectorial: bool | None = None,
):
    """TV denoising of a (Z, Y, X) or (Z, Y, X, C) volume; returns (result, steps, converged,
    lambda per channel, residual variance per channel, sigma per channel or None).

    The parameters mean what they mean for `clpde.denoise_tv`, which calls this for volumes;
    spacing is the voxel's size (z, y, x), in any unit, 1 by default. The stopping test:
    no voxel changed by more than tol (default 1e-3, on [0, 1] data) per iteration over the
    last check_every (default 5) iterations, or max_steps (default 500).
    """
    if sigma is not None and weight is not None:
        raise InputError("give sigma (the noise level) or weight (the strength), not both")
    h = check_spacing(spacing)
    data, layout = to_volume_layout(volume, channel_axis, spacing)
    nc = data.shape[0]
    vectorial = nc > 1 if vectorial is None else bool(vectorial) and nc > 1
    max_steps = check_steps(500 if max_steps is None else max_steps)
    tol = positive("tol", 1e-3 if tol is None else tol)
    check_every = max(1, int(5 if check_every is None else check_every))
    weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
    sigma2 = None
    noise = None
    if weight is not None:
        lam0 = np.full(nc, min(weight_unit / positive("weight", weight), 1e30))
    else:
        if sigma is None:
            sig = np.array([estimate_sigma_volume(c) for c in data])
        else:
            sig = np.full(nc, positive("sigma", sigma) / layout.scale)
        noise = sig * layout.scale
        sigma2 = np.maximum(sig, 1e-6) ** 2
        if vectorial:
            sigma2 = np.full(nc, sigma2.mean())
        lam0 = 1.0 / np.sqrt(sigma2)
    runtime = get_runtime(device)
    grid = VolumeGrid(runtime, data.shape, compute_dtype(None, dtype), h)
    grid.check_fits(14, "3D TV denoising")  # f, u, w, change and three generations of p
    u, steps, converged, lam = _fgp(
        grid, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial
    )
    if sigma2 is not None:
        # noise as large as a channel's own spread: only its mean is that far from the data
        var = data.reshape(nc, -1).var(axis=1)
        spread = sigma2 >= (np.full(nc, var.mean()) if vectorial else var)
        for c in np.flatnonzero(spread):
            u[c] = data[c].mean()
        lam = np.where(spread, 0.0, lam)
    residual = ((u - data) ** 2).reshape(nc, -1).mean(axis=1) * layout.scale**2
    return layout.restore(u), steps, converged, lam / weight_unit, residual, noise


def _fgp(grid: VolumeGrid, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial):
    """Beck and Teboulle's fast projected gradient on the dual; (u, steps, converged, lambda)."""
    rt, q = grid.runtime, grid.runtime.queue
    nc = data.shape[0]
    n = int(np.prod(data.shape[1:]))
    f = cla.to_device(q, data.astype(grid.dtype).reshape(-1))
    gens = [cla.zeros(q, 3 * nc * n, grid.dtype) for _ in range(3)]
    w = cla.empty(q, nc * n, grid.dtype)
    u = f.copy()
    partial = cla.empty(q, nc * 2 * data.shape[2] * data.shape[1], grid.dtype)
    primal_k = rt.kernel("volumes/volume.cl", "volume_dual_primal", grid.dtype)
    lam = np.asarray(lam0, np.float64).copy()
    lam_dev = cla.to_device(q, lam.astype(grid.dtype))
    div_k = rt.kernel("volumes/volume.cl", "volume_dual_div", grid.dtype)
    step_k = rt.kernel("volumes/volume.cl", "volume_dual_step", grid.dtype)
    inv = grid.inverse
    tau = grid.scalar(1.0 / (4.0 * sum(1.0 / s**2 for s in grid.spacing)))
    t, beta, steps, converged = 1.0, 0.0, 0, False
    with progress_bar(progress, max_steps, "clpde denoise_tv (volume)", unit="it") as bar:
        while steps < max_steps and not converged:
            for _ in range(min(check_every, max_steps - steps)):
                p_old, p, p_new = gens
                b = grid.scalar(beta)
                grid.launch(div_k, p.data, p_old.data, f.data, lam_dev.data, b, w.data, *inv)
                grid.launch(
                    step_k, p.data, p_old.data, w.data, p_new.data, b, tau,
                    np.int32(vectorial), *inv,
                )  # fmt: skip
                gens = [p, p_new, p_old]
                t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
                beta, t = (t - 1.0) / t_next, t_next
                steps += 1
            # u = f + div(p) / lambda: w from p itself (beta 0), over lambda per channel
            p = gens[1]
            grid.launch(div_k, p.data, p.data, f.data, lam_dev.data, grid.scalar(0), w.data, *inv)
            rows = _primal(grid, primal_k, w, f, lam_dev, u, partial)
            converged = float(rows[:, 0].max()) < tol * check_every
            if sigma2 is not None and not converged:
                residual = rows[:, 1].sum(axis=1) / n
                if vectorial:
                    lam[:] = max(_LAMBDA_MIN, lam[0] * residual.mean() / sigma2.mean())
                else:
                    held = sigma2 >= data.reshape(nc, -1).var(axis=1)
                    lam = np.where(held, lam, np.maximum(_LAMBDA_MIN, lam * residual / sigma2))
                lam_dev.set(lam.astype(grid.dtype))
            bar.update(steps - bar.n)
    return u.get().astype(np.float64).reshape(data.shape), steps, converged, lam


def _primal(grid: VolumeGrid, kernel, w, f, lam, u, partial) -> np.ndarray:
    """volume_dual_primal over every row; its partials as (nc, 2, rows)."""
    nc, nz, ny, _ = grid.shape
    local = (1, 1, 1) if grid.runtime.is_cpu else None
    kernel(
        grid.runtime.queue, (1, ny, nz), local, w.data, f.data, lam.data, u.data, partial.data,
        *grid.sizes(1),
    )  # fmt: skip
    return partial.get().astype(np.float64).reshape(nc, 2, ny * nz)
