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

This module checks the input and sets up the fidelity and the stopping test; the solvers'
device loops are in rof_solvers.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from ..errors import InputError
from ..fields import Grid, check_fits
from ..imagedata import (
    MAD_TO_STD,
    NOISE_MASK,
    check_steps,
    compute_dtype,
    noise_std,
    positive,
    to_kernel_layout,
)
from ..runtime import get_runtime
from ..volumes.grid import is_volume
from ..volumes.tv import denoise_tv_volume
from . import bounded
from .rof_solvers import gradient_descent, primal_dual, primal_dual_in_tiles

METHODS = ("primal-dual", "gradient")

# Per-method defaults of the stopping parameters (see denoise_tv's docstring).
_DEFAULTS = {
    "primal-dual": {"max_steps": 500, "tol": 1e-3, "check_every": 5},
    "gradient": {"max_steps": 2000, "tol": 2e-4, "check_every": 20},
}
# Large images (more than bounded.LARGE_VALUES values, run in tiles): a looser test and a low
# cap per tile. The result's PSNR is reached long before tol 1e-3 passes (on a 1000 x 1000
# colour photo with noise 10: 30 iterations at tol 5e-3 against 115 at 1e-3, 0.02 dB apart,
# 0.7 grey levels RMS from the minimiser; docs/planar.md), and at 1e-3 a 6000 x 4000 photo
# took over 15 minutes. The cap bounds every tile whatever lambda (sigma) makes of it.
_LARGE_DEFAULTS = {"max_steps": 50, "tol": 5e-3, "check_every": 5}


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
    spacing: ArrayLike | None = None,
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
    2000). Images of more than 2**22 values (a colour photo of 1400 x 1000 or more) run in
    overlapping tiles in bounded memory, each tile stopping at tol 5e-3 or 50 iterations by
    default (lambda's fit, with sigma, keeps 1e-3 and 500); given values apply to both.

    Parameters
    ----------
    image : (rows, columns) or (rows, columns, channels) array
        Integer or float data, never modified; channels need `channel_axis`.
    sigma, weight : float, optional
        The noise level or the strength, as above.
    channel_axis : int, optional
        The axis of the channels of a colour image.
    method : {'primal-dual', 'gradient'}, optional
        The solver, as above (default 'primal-dual').
    device : str or int, optional
        An OpenCL device ('cpu', 'gpu', an index or a name part; see `clpde.devices`).
    max_steps : int, optional
        The cap on iterations, as above.
    tol : float, optional
        The stopping test's threshold on the largest change, on [0, 1] data, as above.
    check_every : int, optional
        Iterations between stopping tests (and primal-dual lambda updates), as above.
    eps : float, optional
        The gradient method's regularisation of |grad u|, on [0, 1] data (default 0.02).
    dt : float, optional
        The gradient method's time step (default: 0.8 of its stability limit).
    lambda_every : int, optional
        The gradient method's steps between lambda updates (default 5).
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    dtype : {float32, float64}, optional
        The device's arithmetic (float32 by default).
    spacing : (3,) array_like, optional
        A volume's voxel size (z, y, x), for (Z, Y, X) and (Z, Y, X, C) arrays (which
        `clpde.volumes` denoises: TV of the physical gradient, primal-dual only); a 3-D
        array without channel_axis is a volume, and giving spacing makes any array one.
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
    if is_volume(image, channel_axis, spacing):  # 3D: clpde/volumes/tv.py
        if method != "primal-dual" or (eps, dt, lambda_every) != (None, None, None):
            raise InputError("volumes are denoised by method='primal-dual' only; leave out "
                             "method, eps, dt and lambda_every")  # fmt: skip
        out, *run, noise = denoise_tv_volume(
            image, sigma, weight, channel_axis, spacing=spacing, device=device,
            max_steps=max_steps, tol=tol, check_every=check_every, progress=progress,
            dtype=dtype, vectorial=vectorial,
        )  # fmt: skip
        info = DenoiseInfo(*run, method, noise, sigma is None and weight is None)
        return (out, info) if return_info else out
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
        _refuse_gradient_options(eps, dt, lambda_every)
        stopping = (max_steps, tol, check_every)
        out, info = _denoise_large(
            image, sigma, weight, channel_axis, runtime, precision, stopping, progress, vectorial
        )
        return (out, info) if return_info else out
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
    max_steps, tol, check_every = _stopping(method, max_steps, tol, check_every)
    # NaN for images too small to estimate from (1 x N): taken as noise-free
    fit = _Fidelity.of(
        sigma,
        weight,
        layout,
        nc,
        vectorial,
        lambda: np.nan_to_num(np.array([noise_std(c) for c in data]), nan=0.0),
    )
    lam0, sigma2 = fit.lam0, fit.sigma2
    if method == "primal-dual":
        _refuse_gradient_options(eps, dt, lambda_every)
        if lam0 is None:
            # Start from weight = sigma, a good guess for natural images; the update corrects it.
            lam0 = 1.0 / np.sqrt(sigma2)
        u, steps, converged, lam = primal_dual(
            grid, data, lam0, sigma2, max_steps, tol, check_every, progress, vectorial
        )
    else:
        eps = positive("eps", 0.02 if eps is None else eps)
        every = max(1, int(lambda_every or 5))
        u, steps, converged, lam = gradient_descent(
            grid, data, lam0, sigma2, eps, dt, max_steps, tol, check_every, every, progress
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
    return out, fit.info(steps, converged, lam, residual, method)


def _refuse_gradient_options(eps, dt, lambda_every) -> None:
    if eps is not None or dt is not None or lambda_every is not None:
        raise InputError(
            "eps, dt and lambda_every belong to method='gradient'; the "
            "primal-dual method uses exact TV and needs none of them"
        )


def _stopping(method: str, max_steps, tol, check_every, defaults=None) -> tuple[int, float, int]:
    """(max_steps, tol, check_every) checked, the method's defaults (or `defaults`) for those
    not given."""
    defaults = defaults or _DEFAULTS[method]
    max_steps = check_steps(defaults["max_steps"] if max_steps is None else max_steps)
    tol = positive("tol", defaults["tol"] if tol is None else tol)
    check_every = max(1, int(defaults["check_every"] if check_every is None else check_every))
    return max_steps, tol, check_every


# A given sigma above this many times the image's own noise estimate (its noisiest channel)
# draws a warning: TV fitted to noise that is not there flattens detail (issue 33: sigma 3x the
# estimate, 27.6 dB against 31.5 with the estimate).
FAR_ABOVE = 2.0


def _warn_if_far_above(sigma: float, estimate, scale: float, depth: int) -> None:
    """Warn when the given sigma is more than FAR_ABOVE times every channel's estimate;
    depth: the calls between denoise_tv and _Fidelity.of."""
    import warnings

    try:
        est = np.nan_to_num(np.asarray(estimate(), np.float64), nan=0.0) * scale
    except InputError:  # too small to estimate from: nothing to compare with
        return
    if est.max() > 0 and sigma > FAR_ABOVE * est.max():
        channels = ", ".join(f"{e:.3g}" for e in est)
        warnings.warn(
            f"sigma {sigma:g} is more than {FAR_ABOVE:g} times the noise estimated in the "
            f"image ({channels}{' per channel' if est.size > 1 else ''}), so TV will smooth "
            "away detail; leave sigma out to use the estimate, or give weight to choose the "
            "strength",
            stacklevel=4 + depth,
        )


@dataclass
class _Fidelity:
    """The fidelity's start on the kernels' [0, 1] data, from sigma or weight: a fixed lam0
    per channel (weight), or sigma2, the noise variance lambda is fitted to (sigma, given or
    estimated); noise is sigma per channel in the image's units, before any sharing."""

    lam0: np.ndarray | None
    sigma2: np.ndarray | None
    noise: np.ndarray | None
    weight_unit: float
    estimated: bool

    @classmethod
    def of(
        cls, sigma, weight, layout, nc: int, vectorial: bool, estimate, depth: int = 0
    ) -> _Fidelity:
        # Float images are scaled by their own range for the kernels; skimage's weight is in
        # the image's units, so lambda on the kernels' [0, 1] data is scale / weight.
        weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
        estimated = weight is None and sigma is None
        if weight is not None:
            # capped where float32 ends: a weight that small next to the range changes nothing
            lam0 = np.full(nc, min(weight_unit / positive("weight", weight), 1e30))
            return cls(lam0, None, None, weight_unit, estimated)
        if sigma is None:
            sig = estimate()
        else:
            sig = np.full(nc, positive("sigma", sigma) / layout.scale)
            _warn_if_far_above(sigma, estimate, layout.scale, depth)
        sigma2 = np.maximum(sig, 1e-6) ** 2
        noise = np.sqrt(sigma2) * layout.scale  # per channel, before any sharing
        if vectorial:
            sigma2 = np.full(nc, sigma2.mean())
        return cls(None, sigma2, noise, weight_unit, estimated)

    def info(self, steps, converged, lam, residual, method: str) -> DenoiseInfo:
        """The run's DenoiseInfo; lam on the [0, 1] data, residual in the image's units."""
        return DenoiseInfo(
            steps, converged, lam / self.weight_unit, residual, method, self.noise, self.estimated
        )


def _denoise_large(
    image, sigma, weight, channel_axis, runtime, precision, stopping, progress, vectorial
) -> tuple[np.ndarray, DenoiseInfo]:
    """denoise_tv's primal-dual run on an image of more than bounded.LARGE_VALUES values: in
    overlapping tiles, converting and restoring a block at a time (see
    rof_solvers.primal_dual_in_tiles), so memory stays bounded whatever the image's size."""
    scaled = bounded.Scaled(image, channel_axis)
    layout, nc = scaled.layout, scaled.nc
    vectorial = nc > 1 if vectorial is None else bool(vectorial) and nc > 1
    tiles = _stopping("primal-dual", *stopping, defaults=_LARGE_DEFAULTS)
    # lambda's fit on the centre keeps the whole-image defaults: lambda moves at every test
    # and needs them to settle (tol given by the caller applies to both)
    fit = _stopping("primal-dual", stopping[0], stopping[1], stopping[2])
    mean, var = bounded.channel_moments(scaled)
    fidelity = _Fidelity.of(
        sigma, weight, layout, nc, vectorial, lambda: noise_std_by_strips(scaled), depth=1
    )
    sigma2 = fidelity.sigma2
    dtype = compute_dtype(None, precision)
    out, steps, converged, lam, residual = primal_dual_in_tiles(
        scaled, dtype, runtime, fidelity.lam0, sigma2, tiles, fit, progress, vectorial
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
    info = fidelity.info(steps, converged, lam, residual * layout.scale**2, "primal-dual")
    return out, info


def estimate_sigma(image: ArrayLike, channel_axis: int | None = None) -> float | np.ndarray:
    """The noise standard deviation of an image, in its own units (0..255 for uint8), per
    channel (an array) when channel_axis is given.

    Robust estimate from the finest scale: the median absolute value of a Laplacian-difference
    residual, scaled as for Gaussian white noise. Needs only numpy (no PyWavelets). Textured
    images read a little high at low noise, as with any single-image estimate
    (docs/planar.md has its accuracy).

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
    sig = np.array([noise_std(c) for c in data]) * layout.scale
    return sig if channel_axis is not None else float(sig[0])


def noise_std_by_strips(scaled: bounded.Scaled) -> np.ndarray:
    """noise_std of each channel, from the residual computed a strip at a time: the
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
                NOISE_MASK[i, j] * u[i : h + i, j : nx - 2 + j] for i in range(3) for j in range(3)
            )
        np.abs(residual, out=residual)
        # in place: np.median would otherwise copy the whole residual (192 MB at 6000 x 4000)
        sig[c] = float(np.median(residual, overwrite_input=True)) * MAD_TO_STD / 6.0
        del residual
    return sig
