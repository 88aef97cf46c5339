"""Total-variation (Rudin-Osher-Fatemi) denoising.

Two solvers of   min_u TV(u) + lambda/2 |u - u0|^2,   both run entirely on the device:

- ``method="primal-dual"`` (default): exact (isotropic) TV, solved in the dual by fast
  projected gradient (kernels/planar/rof.cl). Tens of iterations reach the minimiser to a fraction
  of a grey level.
- ``method="gradient"``: the thesis's explicit gradient descent on
  u_t = div(grad u / |grad u|_eps) - lambda (u - u0) (kernels/planar/planar.cl), which needs
  |grad u| regularised by eps and a time step below eps/4, so many more steps.

With the noise level sigma given, lambda is updated on the device so that the residual
variance tends to sigma^2 (the planar form of thesis eq. C.2), in both methods.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike, DTypeLike

from .._progress import progress_bar
from ..errors import InputError
from ..fields import Field, Grid, PingPong, check_fits
from ..imagedata import check_steps, check_time_step, compute_dtype, positive, to_kernel_layout
from ..runtime import get_runtime
from . import bounded
from .flows import stability_limit

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("planar/planar.cl", "planar/rof.cl")

METHODS = ("primal-dual", "gradient")

# Per-method defaults of the stopping parameters (see denoise_tv's docstring).
_DEFAULTS = {
    "primal-dual": {"max_steps": 500, "tol": 1e-3, "check_every": 5},
    "gradient": {"max_steps": 2000, "tol": 2e-4, "check_every": 20},
}
# Smallest lambda the dynamic update may reach (on [0, 1] data): it only matters when sigma
# exceeds the image's own spread, where the answer tends to the image mean anyway.
_LAMBDA_MIN = 1e-6


@dataclass
class DenoiseInfo:
    """What a denoise_tv run did.

    steps: iterations (primal-dual) or time steps (gradient) run; converged: whether the
    stopping test passed before max_steps; lam: the final lambda per channel, in the same
    units as ``weight`` (so ``denoise_tv(image, weight=1 / lam)`` solves the same problem);
    residual_variance: mean (u - u0)^2 per channel, in the image's units squared;
    sigma: the noise level per channel that lambda was fitted to, in the image's units
    (given or estimated; None when ``weight`` was given); sigma_estimated: whether it was
    estimated from the image.
    """

    steps: int
    converged: bool
    lam: np.ndarray
    residual_variance: np.ndarray
    method: str = "primal-dual"
    sigma: np.ndarray | None = None
    sigma_estimated: bool = False


def denoise_tv(
    image: ArrayLike,
    sigma: float | None = None,
    weight: float | None = None,
    channel_axis: int | None = None,
    *,
    method: str = "primal-dual",
    device: str | int | None = None,
    max_steps: int | None = None,
    tol: float | None = None,
    check_every: int | None = None,
    eps: float | None = None,
    dt: float | None = None,
    lambda_every: int | None = None,
    progress: bool | None = None,
    dtype: DTypeLike | None = None,
    vectorial: bool | None = None,
    return_info: bool = False,
) -> np.ndarray | tuple[np.ndarray, DenoiseInfo]:
    """Total-variation denoising (Rudin-Osher-Fatemi), run on the device to convergence.

    Solves min_u TV(u) + lambda/2 |u - u0|^2. For colour (several channels) TV is by
    default colour-coupled (vectorial): TV(u) = sum over pixels of
    sqrt(sum_c |grad u_c|^2), one lambda for all channels, so that the channels keep their
    edges in the same places; per-channel TV (``vectorial=False``) smooths each channel on
    its own and leaves coloured blotches where one channel's edge is lost and another's
    kept. Give either

    - ``sigma``, the noise standard deviation in the image's units (0..255 for uint8):
      lambda is then found on the device so that the residual variance mean (u - u0)^2
      tends to sigma^2 (thesis eq. C.2); or
    - ``weight``, the denoising strength in scikit-image's convention (lambda = 1/weight;
      weight in the image's units for float images, on the [0, 1] scale for integer ones,
      as skimage.restoration.denoise_tv_chambolle). Larger is smoother.

    With neither, sigma is estimated from the image (``estimate_sigma``).

    method: 'primal-dual' (default; exact TV, fast) or 'gradient' (the thesis's explicit
    scheme with |grad u|_eps; takes ``eps`` (default 0.02, on [0, 1] data), ``dt`` and
    ``lambda_every`` (default 5 steps between lambda updates)). The primal-dual method
    updates lambda at every stopping test.

    Stopping, tested on the device every ``check_every`` iterations: primal-dual stops when
    no pixel of u changed by more than ``tol`` per iteration (on [0, 1] data) over those
    iterations (default 1e-3 every 5; lower tol for more accuracy); gradient when the
    largest change is below tol * check_every * dt (default 2e-4 every 20). Both tests look
    at the largest change of any pixel, so a part of an image stops where it would stop on
    its own, whatever the image's size. ``max_steps`` caps the iterations (default 500 /
    2000).

    Parameters
    ----------
    image : (rows, columns) or (rows, columns, channels) array
        Integer or float data, never modified; channels need `channel_axis`.
    sigma, weight : float, optional
        The noise level or the strength, as above.
    channel_axis : int, optional
        The axis of the channels of a colour image.
    method : {'primal-dual', 'gradient'}
    device, progress, dtype
        As for `clpde.diffuse`.
    max_steps, tol, check_every, eps, dt, lambda_every
        The stopping test and the gradient method's parameters, as above.
    vectorial : bool, optional
        Colour-coupled TV with one lambda (True; the default for several channels with
        the primal-dual method) or each channel with its own TV and lambda (False; the
        gradient method's only form). With sigma, the shared lambda is fitted to the
        channels' mean noise variance. A grey image replicated into n channels gives the
        grey result of weight ``weight / sqrt(n)``, since its vectorial TV is sqrt(n)
        times the grey one.
    return_info : bool
        Also return a `DenoiseInfo`.

    Returns
    -------
    ndarray, or (ndarray, DenoiseInfo) with return_info
        The denoised image (input's shape and dtype); the info holds the steps, whether
        it converged, lambda and the residual variance per channel.

    Raises
    ------
    InputError
        For bad images or parameters (both sigma and weight, an unknown method, vectorial
        with the gradient method, ...), before any work.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> clean = np.zeros((64, 64))
    >>> clean[16:48, 16:48] = 1.0
    >>> noisy = clean + 0.1 * np.random.default_rng(0).standard_normal(clean.shape)
    >>> denoised, info = clpde.denoise_tv(noisy, sigma=0.1, return_info=True)
    >>> info.converged, info.method
    (True, 'primal-dual')
    >>> error = lambda u: float(np.abs(u - clean).mean())
    >>> error(denoised) < error(noisy) / 3
    True
    """
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if sigma is not None and weight is not None:
        raise InputError("give sigma (the noise level) or weight (the strength), not both")
    precision = dtype
    runtime = get_runtime(device)

    # primal-dual: f, u and three dual fields of two components each; gradient: four fields
    def fits(shape):
        check_fits(
            runtime, shape, "TV denoising", 8, dtype=compute_dtype(None, precision), largest=2
        )

    if method == "primal-dual" and bounded.is_large(image):
        if eps is not None or dt is not None or lambda_every is not None:
            raise InputError(
                "eps, dt and lambda_every belong to method='gradient'; the "
                "primal-dual method uses exact TV and needs none of them"
            )
        return _denoise_large(
            image,
            sigma,
            weight,
            channel_axis,
            runtime,
            precision,
            max_steps,
            tol,
            check_every,
            progress,
            vectorial,
            return_info,
        )
    data, layout = to_kernel_layout(image, channel_axis, fits=fits)
    nc, ny, nx = data.shape
    if vectorial is None:
        vectorial = nc > 1 and method == "primal-dual"
    elif vectorial and method != "primal-dual":
        raise InputError(
            "vectorial TV is solved by method='primal-dual' only; leave "
            "vectorial out or set it to False for the gradient method"
        )
    vectorial = bool(vectorial) and nc > 1
    grid = Grid(runtime, nx, ny, nc, 1, compute_dtype(data.dtype, precision))
    defaults = _DEFAULTS[method]
    max_steps = check_steps(defaults["max_steps"] if max_steps is None else max_steps)
    tol = positive("tol", defaults["tol"] if tol is None else tol)
    check_every = max(1, int(defaults["check_every"] if check_every is None else check_every))

    # Float images are scaled by their own range for the kernels; skimage's weight is in the
    # image's units, so lambda on the kernels' [0, 1] data is scale / weight.
    weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
    if weight is not None:
        # capped where float32 ends: a weight that small next to the range changes nothing
        lam0 = np.full(nc, min(weight_unit / positive("weight", weight), 1e30))
        sigma2 = noise = None
    else:
        if sigma is None:
            # NaN for images too small to estimate from (1 x N): taken as noise-free
            sig = np.nan_to_num(np.array([_noise_std(c) for c in data]), nan=0.0)
        else:
            sig = np.full(nc, positive("sigma", sigma) / layout.scale)
        sigma2 = np.maximum(sig, 1e-6) ** 2
        noise = np.sqrt(sigma2) * layout.scale  # per channel, before any sharing
        if vectorial:
            sigma2 = np.full(nc, sigma2.mean())
        lam0 = None

    if method == "primal-dual":
        if eps is not None or dt is not None or lambda_every is not None:
            raise InputError(
                "eps, dt and lambda_every belong to method='gradient'; the "
                "primal-dual method uses exact TV and needs none of them"
            )
        if lam0 is None:
            # Start from weight = sigma, a good guess for natural images; the update corrects it.
            lam0 = 1.0 / np.sqrt(sigma2)
        u, steps, converged, lam = _primal_dual(
            grid, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial
        )
    else:
        eps = positive("eps", 0.02 if eps is None else eps)
        u, steps, converged, lam = _gradient(
            grid,
            data,
            lam0,
            sigma2,
            eps,
            dt,
            max_steps,
            tol,
            check_every,
            max(1, int(lambda_every or 5)),
            progress,
        )
    if sigma2 is not None:
        # Noise as large as the image's own spread: the only image that far from the data
        # is its mean (lambda -> 0), which the iterations approach only slowly.
        spread = sigma2 >= data.var(axis=(1, 2))
        if vectorial:  # one lambda: all channels or none
            spread[:] = sigma2.mean() >= data.var(axis=(1, 2)).mean()
        u[spread] = data[spread].mean(axis=(1, 2))[:, None, None]
        lam = np.where(spread, 0.0, lam)
    out = layout.restore(u)
    if not return_info:
        return out
    residual = ((u - data) ** 2).mean(axis=(1, 2)) * layout.scale**2
    return out, DenoiseInfo(
        steps,
        converged,
        lam / weight_unit,
        residual,
        method,
        noise,
        weight is None and sigma is None,
    )


def _denoise_large(
    image,
    sigma,
    weight,
    channel_axis,
    runtime,
    precision,
    max_steps,
    tol,
    check_every,
    progress,
    vectorial,
    return_info,
):
    """denoise_tv's primal-dual run on an image of more than bounded.LARGE_VALUES values: in
    overlapping tiles, converting and restoring a block at a time (see
    denoise_large), so memory stays bounded whatever the image's size."""
    scaled = bounded.Scaled(image, channel_axis)
    layout, nc = scaled.layout, scaled.nc
    vectorial = nc > 1 if vectorial is None else bool(vectorial) and nc > 1
    defaults = _DEFAULTS["primal-dual"]
    max_steps = check_steps(defaults["max_steps"] if max_steps is None else max_steps)
    tol = positive("tol", defaults["tol"] if tol is None else tol)
    check_every = max(1, int(defaults["check_every"] if check_every is None else check_every))
    weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
    mean, var = bounded.channel_moments(scaled)
    if weight is not None:
        lam0 = np.full(nc, min(weight_unit / positive("weight", weight), 1e30))
        sigma2 = noise = None
    else:
        if sigma is None:
            sig = noise_std_by_strips(scaled)
        else:
            sig = np.full(nc, positive("sigma", sigma) / layout.scale)
        sigma2 = np.maximum(sig, 1e-6) ** 2
        noise = np.sqrt(sigma2) * layout.scale
        if vectorial:
            sigma2 = np.full(nc, sigma2.mean())
        lam0 = None
    dtype = compute_dtype(None, precision)
    out, steps, converged, lam, residual = denoise_large(
        scaled, dtype, runtime, lam0, sigma2, max_steps, tol, check_every, progress, vectorial
    )
    if sigma2 is not None:
        # as in denoise_tv: noise beyond a channel's own spread leaves only its mean
        spread = sigma2 >= var
        if vectorial:
            spread[:] = sigma2.mean() >= var.mean()
        for c in np.flatnonzero(spread):
            scaled.out_channels[c] = scaled.restore_value(mean[c])
            residual[c] = var[c]
        lam = np.where(spread, 0.0, lam)
    if not return_info:
        return out
    return out, DenoiseInfo(
        steps,
        converged,
        lam / weight_unit,
        residual * layout.scale**2,
        "primal-dual",
        noise,
        weight is None and sigma is None,
    )


# The difference of two discrete Laplacians (Immerkaer 1996): it annihilates constant, linear
# and most of the quadratic content of an image, and turns white noise of deviation sigma
# into values of deviation 6 sigma (the root of the sum of its squared weights, 36).
_NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
_MAD_TO_STD = 1.0 / 0.6744897501960817  # median |x| of a unit normal variable


def _noise_std(u: np.ndarray) -> float:
    """Noise deviation of one 2-D channel: the median absolute value of its fine-scale
    residual, as for a normal variable. The median, not the mean, so that the edges and
    texture where the residual is large do not count as noise."""
    ny, nx = u.shape
    if ny < 3 or nx < 3:
        raise InputError(
            f"an image of {nx}x{ny} pixels is too small to estimate its noise "
            "from; give sigma or weight"
        )
    r = sum(
        _NOISE_MASK[i, j] * u[i : ny - 2 + i, j : nx - 2 + j] for i in range(3) for j in range(3)
    )
    return float(np.median(np.abs(r))) * _MAD_TO_STD / 6.0


def estimate_sigma(image: ArrayLike, channel_axis: int | None = None) -> float | np.ndarray:
    """The noise standard deviation of an image, in its own units (0..255 for uint8), per
    channel (an array) when channel_axis is given.

    Robust estimate from the finest scale: the median absolute value of a Laplacian-difference
    residual, scaled as for Gaussian white noise. Needs only numpy (no PyWavelets). Within a
    few percent on photos with noise of 2% of the range and more; textured images read a
    little high at low noise, as with any single-image estimate.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.planar.rof import estimate_sigma
    >>> ramp = np.linspace(0, 1, 128)[None, :] * np.ones((128, 1))
    >>> noisy = ramp + 0.05 * np.random.default_rng(1).standard_normal(ramp.shape)
    >>> round(estimate_sigma(noisy), 2)
    0.05
    """
    data, layout = to_kernel_layout(image, channel_axis)
    sig = np.array([_noise_std(c) for c in data]) * layout.scale
    return sig if channel_axis is not None else float(sig[0])


def _primal_dual(
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


def _gradient(
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
    step_k = grid.kernel("planar/planar.cl", "rof_step")
    rows_k = grid.kernel("planar/planar.cl", "rof_lambda_rows")
    finish_k = grid.kernel("planar/planar.cl", "rof_lambda_finish")
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


# ---- large images: strips and overlapping tiles (bounded.py) ---------------------------------
def noise_std_by_strips(scaled: bounded.Scaled) -> np.ndarray:
    """rof._noise_std of each channel, from the residual computed a strip at a time: the
    same float64 values (each residual value reads the same nine numbers in the same order),
    so the same median, without the whole image's float64 copy and its temporaries."""

    ny, nx = scaled.ny, scaled.nx
    if ny < 3 or nx < 3:
        raise InputError(
            f"an image of {nx}x{ny} pixels is too small to estimate its noise "
            "from; give sigma or weight"
        )
    sig = np.empty(scaled.nc)
    for c in range(scaled.nc):
        residual = np.empty((ny - 2, nx - 2))
        for r in range(0, ny - 2, bounded.STRIP_ROWS):
            stop = min(r + bounded.STRIP_ROWS, ny - 2)
            u = scaled.block(slice(r, stop + 2), slice(None), c)[0]
            h = stop - r
            residual[r:stop] = sum(
                _NOISE_MASK[i, j] * u[i : h + i, j : nx - 2 + j] for i in range(3) for j in range(3)
            )
        np.abs(residual, out=residual)
        sig[c] = float(np.median(residual)) * _MAD_TO_STD / 6.0
    return sig


def denoise_large(
    scaled: bounded.Scaled,
    grid_dtype,
    runtime,
    lam0,
    sigma2,
    max_steps,
    tol,
    check_every,
    progress,
    vectorial,
):
    """denoise_tv of a large image in overlapping tiles (bounded.TILE_CORE kept,
    bounded.TILE_MARGIN read on each side), each run to its own convergence with one lambda
    per channel for the whole image. With sigma, lambda is first fitted (the dynamic
    update) on the central region of the image of bounded.LAMBDA_SAMPLE_VALUES values, then
    held for every tile.

    Not bit for bit the whole-image run: a tile's pixels see the image only to bounded.TILE_MARGIN
    beyond its core and stop by their own convergence; the fitted lambda is that of the
    central region, not of the whole image. Returns (result, steps (the most a tile ran),
    converged (every tile), lambda, residual variance per channel in [0, 1] units)."""

    nc, ny, nx = scaled.nc, scaled.ny, scaled.nx
    lam = np.asarray(lam0, np.float64) if lam0 is not None else None
    if sigma2 is not None:
        side = int(np.sqrt(bounded.LAMBDA_SAMPLE_VALUES / nc))
        h, w = min(ny, side), min(nx, side)
        rows = slice((ny - h) // 2, (ny - h) // 2 + h)
        cols = slice((nx - w) // 2, (nx - w) // 2 + w)
        sample = scaled.block(rows, cols)
        grid = Grid(runtime, w, h, nc, 1, grid_dtype)
        _, _, _, lam = _primal_dual(
            grid,
            sample,
            1.0 / np.sqrt(sigma2),
            sigma2,
            max_steps,
            tol,
            check_every,
            False,
            vectorial,
        )
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
            u, steps, done, _ = _primal_dual(
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
