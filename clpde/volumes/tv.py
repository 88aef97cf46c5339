"""Total-variation (ROF) denoising of 3D volumes: min_u TV(u) + lambda/2 |u - u0|^2 with
TV(u) = sum over voxels of |grad u|, grad the forward difference over the voxel spacing, so a
thick slice's difference counts for its physical gradient. Solved in the dual by fast
projected gradient (kernels/volumes/volume.cl, as kernels/planar/rof.cl does in 2D), with
lambda fitted on the host to the noise level when sigma is given or estimated."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .._progress import progress_bar
from ..errors import DeviceMemoryError, InputError
from ..imagedata import check_steps, compute_dtype, positive
from ..runtime import get_runtime
from .grid import VolumeGrid, check_spacing, to_volume_layout

KERNEL_FILES = ("volumes/volume.cl",)

# The difference of two discrete Laplacians (Immerkaer 1996), applied in each slice: it turns
# white noise of deviation sigma into values of deviation 6 sigma.
_NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
_MAD_TO_STD = 1.0 / 0.6744897501960817
_LAMBDA_MIN = 1e-6
FIELDS = 14  # device copies of the volume: f, u, w and three generations of the 3-vector p
# Slabs: planes per slab upload, None to size them by the device's memory (tests force few)
TILE_PLANES = None


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
    u, steps, converged, lam = _fgp(
        runtime, compute_dtype(None, dtype), h, data, lam0, sigma2, max_steps, tol, check_every,
        progress, vectorial,
    )  # fmt: skip
    if sigma2 is not None:
        # noise as large as a channel's own spread: only its mean is that far from the data
        var = data.reshape(nc, -1).var(axis=1)
        spread = sigma2 >= (np.full(nc, var.mean()) if vectorial else var)
        for c in np.flatnonzero(spread):
            u[c] = data[c].mean()
        lam = np.where(spread, 0.0, lam)
    residual = ((u - data) ** 2).reshape(nc, -1).mean(axis=1) * layout.scale**2
    return layout.restore(u), steps, converged, lam / weight_unit, residual, noise


class _Slab:
    """The FGP's device state over the planes [a, b) of the volume: f, u, the dual p in three
    generations (p_old, p, p_new), w and lambda, and the steps that move it."""

    def __init__(self, runtime, real, h, data, a, b):
        self.a, self.b = a, b
        nc = data.shape[0]
        self.grid = VolumeGrid(runtime, (nc, b - a) + data.shape[2:], real, h)
        self.n = int(np.prod(self.grid.shape[1:]))
        q, g = runtime.queue, self.grid
        self.f = cla.to_device(q, np.ascontiguousarray(data[:, a:b], g.dtype).reshape(-1))
        self.u = self.f.copy()
        self.gens = [cla.zeros(q, 3 * nc * self.n, g.dtype) for _ in range(3)]
        self.w = cla.empty(q, nc * self.n, g.dtype)
        self.partial = cla.empty(q, nc * 2 * g.shape[2] * g.shape[1], g.dtype)
        self.lam = cla.empty(q, nc, g.dtype)
        self.div_k = runtime.kernel("volumes/volume.cl", "volume_dual_div", g.dtype)
        self.step_k = runtime.kernel("volumes/volume.cl", "volume_dual_step", g.dtype)
        self.primal_k = runtime.kernel("volumes/volume.cl", "volume_dual_primal", g.dtype)
        self.tau = g.scalar(1.0 / (4.0 * sum(1.0 / s**2 for s in g.spacing)))

    def load(self, gens, u) -> None:
        """The host's state (p's generations as (3 nc, nz, ny, nx), u as (nc, nz, ny, nx))."""
        for dev, host in zip(self.gens, gens, strict=True):
            dev.set(np.ascontiguousarray(host[:, self.a : self.b], self.grid.dtype).reshape(-1))
        self.u.set(np.ascontiguousarray(u[:, self.a : self.b], self.grid.dtype).reshape(-1))

    def store(self, gens, u, z0, z1) -> None:
        """Planes [z0, z1) of the state into the host's arrays."""
        own = slice(z0 - self.a, z1 - self.a)
        shape = self.grid.shape
        for dev, host in zip(self.gens, gens, strict=True):
            host[:, z0:z1] = dev.get().reshape((3 * shape[0],) + shape[1:])[:, own]
        u[:, z0:z1] = self.u.get().reshape(shape)[:, own]

    def run(self, lam, betas, vectorial) -> np.ndarray:
        """One FGP iteration per beta, then u = f + div(p) / lambda; the primal's partials
        as (nc, 2, rows), rows (z, y) of this slab."""
        g, inv = self.grid, self.grid.inverse
        self.lam.set(np.asarray(lam, g.dtype))
        for beta in betas:
            p_old, p, p_new = self.gens
            b = g.scalar(beta)
            g.launch(self.div_k, p.data, p_old.data, self.f.data, self.lam.data, b, self.w.data,
                     *inv)  # fmt: skip
            g.launch(
                self.step_k, p.data, p_old.data, self.w.data, p_new.data, b, self.tau,
                np.int32(vectorial), *inv,
            )  # fmt: skip
            self.gens = [p, p_new, p_old]
        p = self.gens[1]
        zero = g.scalar(0)
        g.launch(self.div_k, p.data, p.data, self.f.data, self.lam.data, zero, self.w.data, *inv)
        return _primal(g, self.primal_k, self.w, self.f, self.lam, self.u, self.partial)


def _slabs(nz: int, planes: int, ghost: int) -> list[tuple[int, int, int, int]]:
    """(a, b, z0, z1): slabs of own planes [z0, z1) uploaded as [a, b), `ghost` planes more on
    either side, at most `planes` in all; one slab when the volume fits."""
    if planes >= nz:
        return [(0, nz, 0, nz)]
    own = planes - 2 * ghost
    if own < 1:
        raise DeviceMemoryError(
            f"3D TV denoising needs {2 * ghost + 1} planes of the volume on the device at "
            f"once, but it holds {planes}; crop the volume in y or x, or lower check_every"
        )
    return [
        (max(0, z0 - ghost), min(nz, z0 + own + ghost), z0, min(nz, z0 + own))
        for z0 in range(0, nz, own)
    ]


def _fgp(runtime, real, h, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial):
    """Beck and Teboulle's fast projected gradient on the dual; (u, steps, converged, lambda).

    A volume too large for the device runs in slabs along z, each round of check_every
    iterations on each slab with check_every + 1 ghost planes (an iteration reads one plane
    away, the primal one more), the state kept on the host between rounds; one slab stays
    on the device throughout."""
    nc, nz, ny, nx = data.shape
    n = nz * ny * nx
    slabs = _slabs(nz, _planes_that_fit(runtime, data.shape, real), check_every + 1)
    whole = _Slab(runtime, real, h, data, 0, nz) if len(slabs) == 1 else None
    gens = None if whole else [np.zeros((3 * nc, nz, ny, nx)) for _ in range(3)]
    u = None if whole else data.copy()
    lam = np.asarray(lam0, np.float64).copy()
    t, beta, steps, converged = 1.0, 0.0, 0, False
    with progress_bar(progress, max_steps, "clpde denoise_tv (volume)", unit="it") as bar:
        while steps < max_steps and not converged:
            betas = []
            for _ in range(min(check_every, max_steps - steps)):
                betas.append(beta)
                t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
                beta, t = (t - 1.0) / t_next, t_next
                steps += 1
            if whole:
                rows = whole.run(lam, betas, vectorial)
            else:
                # the round's results go to new arrays: a later slab's ghosts are the
                # planes an earlier slab owns, as they were before the round
                parts, new_gens, new_u = [], [np.empty_like(g) for g in gens], np.empty_like(u)
                for a, b, z0, z1 in slabs:
                    slab = _Slab(runtime, real, h, data, a, b)
                    slab.load(gens, u)
                    part = slab.run(lam, betas, vectorial)
                    parts.append(part[:, :, (z0 - a) * ny : (z1 - a) * ny])
                    slab.store(new_gens, new_u, z0, z1)
                gens, u, rows = new_gens, new_u, np.concatenate(parts, axis=2)
            converged = float(rows[:, 0].max()) < tol * check_every
            if sigma2 is not None and not converged:
                residual = rows[:, 1].sum(axis=1) / n
                if vectorial:
                    lam[:] = max(_LAMBDA_MIN, lam[0] * residual.mean() / sigma2.mean())
                else:
                    held = sigma2 >= data.reshape(nc, -1).var(axis=1)
                    lam = np.where(held, lam, np.maximum(_LAMBDA_MIN, lam * residual / sigma2))
            bar.update(steps - bar.n)
    if whole:
        u = whole.u.get().astype(np.float64).reshape(data.shape)
    return u, steps, converged, lam


def _planes_that_fit(runtime, shape, real) -> int:
    """How many z planes of the FIELDS device copies of a (nc, nz, ny, nx) volume the device
    holds (TILE_PLANES when set)."""
    if TILE_PLANES is not None:
        return int(TILE_PLANES)
    nc, nz, ny, nx = shape
    plane = nc * ny * nx * np.dtype(real).itemsize
    return int(min(runtime.global_mem // (FIELDS * plane), runtime.max_alloc // (3 * plane)))


def _primal(grid: VolumeGrid, kernel, w, f, lam, u, partial) -> np.ndarray:
    """volume_dual_primal over every row; its partials as (nc, 2, rows)."""
    nc, nz, ny, _ = grid.shape
    local = (1, 1, 1) if grid.runtime.is_cpu else None
    kernel(
        grid.runtime.queue, (1, ny, nz), local, w.data, f.data, lam.data, u.data, partial.data,
        *grid.sizes(1),
    )  # fmt: skip
    return partial.get().astype(np.float64).reshape(nc, 2, ny * nz)
