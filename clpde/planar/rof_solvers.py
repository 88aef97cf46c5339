"""The device loops of denoise_tv's two solvers (see rof.py): the fast projected gradient on
the dual of exact TV (kernels/planar/rof.cl), over a whole image or in overlapping tiles, and
the thesis's explicit gradient descent (kernels/planar/planar.cl), each with lambda updated
on the device when the noise level is given."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .._progress import progress_bar
from ..fields import Field, Grid, PingPong
from ..imagedata import check_time_step
from . import bounded
from .flows import stability_limit

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("planar/planar.cl", "planar/rof.cl")

# Smallest lambda the dynamic update may reach (on [0, 1] data): it only matters when sigma
# exceeds the image's own spread, where the answer tends to the image mean anyway.
_LAMBDA_MIN = 1e-6


def primal_dual(
    grid: Grid, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial: bool = False
):
    """Fast projected gradient on the dual (kernels/planar/rof.cl); returns (u, steps, converged,
    lambda). vectorial: the colour-coupled model, one lambda shared by the channels (lam0
    and sigma2 then hold that value for every channel)."""
    q = grid.runtime.queue
    nc, ny = grid.nc, grid.ny
    f = Field.from_host(grid, data)  # Neumann (mirrored) ghosts, as rof.cl expects
    # Three generations of the dual field (p_old, p, p_new), rotated each iteration, with
    # (px, py) interleaved per padded cell. Ghosts that the reflection makes zero stay zero;
    # the step writes the others.
    nbytes = 2 * nc * grid.plane * grid.dtype.itemsize
    grid.runtime.check_alloc(nbytes, "dual field")
    gens = [cla.zeros(q, (nc, grid.plane, 2), grid.dtype) for _ in range(3)]
    u = f.copy()
    lam = cla.to_device(q, np.asarray(lam0, grid.dtype))
    partial = cla.empty(q, nc * 4 * ny, grid.dtype)
    rows_k = grid.kernel("planar/rof.cl", "rof_dual_rows")
    if vectorial:
        # one launch covers every channel: the projection needs the whole cell's vector
        cells = Grid(grid.runtime, grid.nx, ny, 1, grid.ghost, grid.dtype)
        step_k = grid.kernel("planar/rof.cl", "rof_dual_step_vec")
        lambda_k = grid.kernel("planar/rof.cl", "rof_dual_lambda_vec")
    else:
        step_k = grid.kernel("planar/rof.cl", "rof_dual_step")
        lambda_k = grid.kernel("planar/rof.cl", "rof_dual_lambda")
    if sigma2 is not None:
        # 0 holds lambda: channels whose sigma is beyond their spread get the mean anyway
        # (see denoise_tv), and a lambda falling towards 0 would only slow the stopping test.
        spread = data.var(axis=(1, 2))
        if vectorial:
            held = sigma2.mean() >= spread.mean()
            inv_vec = grid.scalar(0.0 if held else 1.0 / (grid.nx * ny * nc * sigma2.mean()))
        else:
            inv = np.where(sigma2 >= spread, 0.0, 1.0 / (grid.nx * ny * sigma2))
            inv_n_sigma2 = cla.to_device(q, inv.astype(grid.dtype))
    t, beta = 1.0, 0.0
    steps, converged = 0, False
    bar = progress_bar(progress, max_steps, "clpde denoise_tv", unit="it")
    with bar:
        while steps < max_steps and not converged:
            for _ in range(min(check_every, max_steps - steps)):
                p_old, p, p_new = gens
                if vectorial:
                    cells.launch(
                        step_k,
                        p.data,
                        p_old.data,
                        p_new.data,
                        f.data.data,
                        lam.data,
                        grid.scalar(beta),
                        np.int32(nc),
                    )
                else:
                    grid.launch(
                        step_k,
                        p.data,
                        p_old.data,
                        p_new.data,
                        f.data.data,
                        lam.data,
                        grid.scalar(beta),
                    )
                gens = [p, p_new, p_old]
                t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
                beta, t = (t - 1.0) / t_next, t_next
                steps += 1
            # u = f + div(p)/lambda and the check's row partials; only nc * 4 * ny numbers
            # come back to the host.
            _launch_rows(
                grid, rows_k, gens[1].data, f.data.data, lam.data, u.data.data, partial.data
            )
            converged = _largest_change(partial.get(), nc, ny) < tol * check_every
            if sigma2 is not None and not converged:
                if vectorial:
                    lambda_k(
                        q,
                        (1,),
                        (1,),
                        partial.data,
                        lam.data,
                        np.int32(ny),
                        np.int32(nc),
                        inv_vec,
                        grid.scalar(_LAMBDA_MIN),
                    )
                else:
                    lambda_k(
                        q,
                        (nc,),
                        (1,),
                        partial.data,
                        lam.data,
                        np.int32(ny),
                        inv_n_sigma2.data,
                        grid.scalar(_LAMBDA_MIN),
                    )
            bar.update(steps - bar.n)
    return u.to_host().astype(np.float64), steps, converged, lam.get().astype(np.float64)


def _launch_rows(grid: Grid, kernel, *args):
    """A row-sum kernel: one work-item per interior row and channel, on every device.

    The local size is fixed on CPUs, as grid launches do: PoCL compiles a kernel anew for
    each local size it is given.
    """
    local = (1, 1, 1) if grid.runtime.is_cpu else None
    kernel(grid.runtime.queue, (1, grid.ny, grid.nc), local, *args, *grid.args(grid.nx))


def _largest_change(partials: np.ndarray, nc: int, ny: int) -> float:
    """The largest change of any pixel of any channel since the last check ([0, 1] units)."""
    return float(partials.reshape(nc, 4, ny)[:, 3].max())


def gradient_descent(
    grid: Grid, data, lam0, sigma2, eps, dt, max_steps, tol, check_every, lambda_every, progress
):
    """The thesis's gradient descent (kernels/planar/planar.cl); returns (u, steps, converged,
    lambda)."""
    q = grid.runtime.queue
    nc, ny, nx = grid.nc, grid.ny, grid.nx
    if lam0 is None:
        lam0 = np.zeros(nc)  # with sigma given, lambda grows from zero by eq. C.2
    lam_max = 0.0 if sigma2 is not None else float(lam0.max())
    # With dynamic lambda the limit is re-checked against lambda as it grows (see below).
    dt = check_time_step(dt, stability_limit("rof", eps, lam_max), f"ROF (eps={eps:g})")

    u0 = Field.from_host(grid, data)
    pair = PingPong(u0.copy())
    previous = u0.copy()
    lam = cla.to_device(q, lam0.astype(grid.dtype))
    partial = cla.empty(q, (nc, ny), grid.dtype)
    step_k = grid.kernel("planar/planar.cl", "planar_rof_step")
    rows_k = grid.kernel("planar/planar.cl", "planar_rof_lambda_rows")
    finish_k = grid.kernel("planar/planar.cl", "planar_rof_lambda_finish")
    eps2 = grid.scalar(eps * eps)

    steps = 0
    converged = False
    bar = progress_bar(progress, max_steps, "clpde denoise_tv", unit="step")
    with bar:
        while steps < max_steps:
            if sigma2 is not None and steps % lambda_every == 0:
                _launch_rows(grid, rows_k, pair.cur.data.data, u0.data.data, partial.data, eps2)
                for c in range(nc):  # one work-item at channel c (sigma may differ)
                    finish_k(
                        q,
                        (1,),
                        (1,),
                        partial.data,
                        lam.data,
                        np.int32(ny),
                        grid.scalar(1.0 / (nx * ny * sigma2[c])),
                        global_offset=(c,),
                    )
                # (C.2) divides by sigma^2: lambda can jump at any update, and a step that
                # was stable before it would blow up (found by fuzzing: 1e12 for sigma=1e-3)
                top = min(float(np.nan_to_num(lam.get().max(), nan=0.0)), 1e30)
                if dt > stability_limit("rof", eps, top):
                    dt = 0.8 * stability_limit("rof", eps, top)
            grid.launch(
                step_k,
                pair.cur.data.data,
                pair.nxt.data.data,
                u0.data.data,
                lam.data,
                grid.scalar(dt),
                eps2,
            )  # the step also refreshes the ghosts
            pair.swap()
            steps += 1
            if steps % check_every == 0 or steps == max_steps:
                change = pair.cur.max_abs_diff(previous)  # one small read per check
                bar.update(steps - bar.n)
                if change < tol * check_every * dt:
                    converged = True
                    break
                previous.assign(pair.cur)
    return pair.cur.to_host(), steps, converged, lam.get().astype(np.float64)


def primal_dual_in_tiles(
    scaled: bounded.Scaled, grid_dtype, runtime, lam0, sigma2, stopping, fit, progress, vectorial
):
    """denoise_tv of a large image in overlapping tiles (bounded.TILE_CORE kept,
    bounded.TILE_MARGIN read on each side), each run to its own convergence or to its cap,
    stopping = (max_steps, tol, check_every), with one lambda per channel for the whole
    image. With sigma, lambda is first fitted (the dynamic update, stopping `fit`) on the
    central region of the image of bounded.LAMBDA_SAMPLE_VALUES values, then held for every
    tile.

    Not bit for bit the whole-image run: a tile's pixels see the image only to bounded.TILE_MARGIN
    beyond its core and stop by their own convergence; the fitted lambda is that of the
    central region, not of the whole image. Progress: the fit's iterations, then the tiles.
    Returns (result, steps (the most a tile ran), converged (every tile), lambda, residual
    variance per channel in [0, 1] units)."""

    nc, ny, nx = scaled.nc, scaled.ny, scaled.nx
    max_steps, tol, check_every = stopping
    lam = np.asarray(lam0, np.float64) if lam0 is not None else None
    if sigma2 is not None:
        side = int(np.sqrt(bounded.LAMBDA_SAMPLE_VALUES / nc))
        h, w = min(ny, side), min(nx, side)
        rows = slice((ny - h) // 2, (ny - h) // 2 + h)
        cols = slice((nx - w) // 2, (nx - w) // 2 + w)
        sample = scaled.block(rows, cols)
        grid = Grid(runtime, w, h, nc, 1, grid_dtype)
        lam0 = 1.0 / np.sqrt(sigma2)
        _, _, _, lam = primal_dual(grid, sample, lam0, sigma2, *fit, progress, vectorial)
        del sample
    steps_max, converged = 0, True
    sq = np.zeros(nc)
    core, margin = bounded.TILE_CORE, bounded.TILE_MARGIN
    tiles = [
        (ky, kx, ry, rx)
        for ky, ry in bounded.spans(ny, core, margin)
        for kx, rx in bounded.spans(nx, core, margin)
    ]

    with progress_bar(progress, len(tiles), "clpde denoise_tv", unit="tile") as bar:
        for ky, kx, ry, rx in tiles:
            block = scaled.block(ry, rx)
            grid = Grid(runtime, block.shape[2], block.shape[1], nc, 1, grid_dtype)
            u, steps, done, _ = primal_dual(
                grid, block, lam, None, max_steps, tol, check_every, False, vectorial
            )
            keep = (
                slice(None),
                slice(ky.start - ry.start, ky.stop - ry.start),
                slice(kx.start - rx.start, kx.stop - rx.start),
            )
            sq += ((u[keep] - block[keep]) ** 2).sum(axis=(1, 2))
            scaled.restore(u[keep], ky, kx)
            steps_max, converged = max(steps_max, steps), converged and done
            bar.update(1)
    return scaled.out, steps_max, converged, lam, sq / (ny * nx)
