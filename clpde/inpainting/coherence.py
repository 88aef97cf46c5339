"""Coherence transport inpainting, after Bornemann & Maerz, "Fast image inpainting based on
coherence transport" (J. Math. Imaging Vision 28, 2007).

The hole is filled from its border inwards, in the order of the distance to the known
pixels. Each pixel gets a weighted mean of the pixels already known in a disc of radius
epsilon around it; the weights favour the pixels lying along the coherence direction of
a structure tensor, so that edges and stripes arriving at the border are continued
straight across the hole, and fall back to a distance-weighted (isotropic) mean where the
tensor sees no coherent structure.

The paper walks the pixels one at a time by fast marching. Here they go one distance shell
at a time (shell k: the hole pixels at Euclidean distance in (k - 1, k] from the known
pixels), all pixels of a shell in parallel on the device, each reading only pixels known
before its shell. Per shell, on the device:

- u_sigma = K_sigma * (known u) / K_sigma * known: the known pixels, smoothed (sigma);
- J = K_rho * sum over channels of grad u_sigma grad u_sigma^T (normalized over the
  pixels whose gradient is known): one tensor for all colour channels (rho);
- n, the eigenvector of J's larger eigenvalue (across the structure), and the coherence
  q = ((l1 - l2) / (l1 + l2))^2 in [0, 1];
- u(x) = sum_y w u(y) / sum_y w over the known y with |y - x| <= epsilon,
      w(x, y) = exp(-mu^2 / (2 epsilon^2) <n, y - x>^2) / |y - x|,   mu = kappa q.

So kappa = 0 gives the isotropic 1/|y - x| mean, and a large kappa a transport along the
structure wherever it is coherent. The map from coherence to the guidance strength mu
(kappa times the squared normalized eigenvalue gap) is our choice, in the spirit of the
paper's switch between diffusion and directional transport; epsilon, kappa, sigma and rho
default to the values of the paper's examples as we know them (5, 25, 1.4, 4). This was
written from the paper's description of the method, without its full text at hand; the
weight's exact form is worth checking against it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from ..errors import InputError
from .poisson import box_around
from .registry import register

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/coherence.cl",)


@dataclass(frozen=True)
class CoherenceOptions:
    """method="coherence"'s options (the module docstring), checked on construction.

    Parameters
    ----------
    epsilon : float
        Radius of the disc of known pixels each pixel's mean reads (> 1.5).
    kappa : float
        Strength of the guidance along the coherence direction (0: isotropic).
    sigma : float
        The pre-smoothing's Gaussian width (> 0).
    rho : float
        The structure tensor's window width (> 0).
    """

    epsilon: float = 5.0
    kappa: float = 25.0
    sigma: float = 1.4
    rho: float = 4.0

    def __post_init__(self) -> None:
        for name, low in (("epsilon", 1.5), ("sigma", 0.0), ("rho", 0.0)):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= low:
                raise InputError(f"{name} must be a number > {low:g}, not {value!r}")
        if not np.isfinite(self.kappa) or self.kappa < 0:
            raise InputError(f"kappa must be a number >= 0, not {self.kappa!r}")


DEFAULTS = asdict(CoherenceOptions())


def gaussian_taps(s: float) -> np.ndarray:
    r = max(1, int(np.ceil(3 * s)))
    x = np.arange(-r, r + 1)
    w = np.exp(-0.5 * (x / s) ** 2)
    return w / w.sum()


def margin(epsilon=DEFAULTS["epsilon"], sigma=DEFAULTS["sigma"], rho=DEFAULTS["rho"]) -> int:
    """Pixels of context a hole needs: the disc, plus the smoothing and tensor windows."""
    return int(np.ceil(epsilon)) + len(gaussian_taps(sigma)) // 2 + len(gaussian_taps(rho)) // 2 + 1


def MARGIN(
    omega=None, *, epsilon=DEFAULTS["epsilon"], sigma=DEFAULTS["sigma"], rho=DEFAULTS["rho"], **_
):
    """The registry's margin: MARGIN(omega, **params) -> pixels (omega is not needed)."""
    return margin(epsilon, sigma, rho)


def _check(epsilon, kappa, sigma, rho):
    CoherenceOptions(epsilon, kappa, sigma, rho)


def shells(omega: np.ndarray, reach: int = 6) -> np.ndarray:
    """Shell number of each hole pixel (0 outside): ceil of its distance to the known pixels.

    Thin holes (every pixel within `reach` of a known one, as for text and scratches): the
    known mask shifted by each offset in the order of its length, the first hit giving the
    distance, ten times quicker than the full distance transform of the box; thicker ones:
    scipy's exact Euclidean distance transform. Both give the same shells."""
    ny, nx = omega.shape
    known = np.pad(~omega, reach, constant_values=False)
    remaining = omega.copy()
    out = np.zeros(omega.shape, np.int64)
    for d2, dy, dx in _offsets(reach):
        hit = remaining & known[reach + dy : reach + dy + ny, reach + dx : reach + dx + nx]
        if hit.any():
            out[hit] = int(np.ceil(np.sqrt(d2) - 1e-9))
            remaining &= ~hit
            if not remaining.any():
                return out
    if not remaining.any():
        return out
    dist = ndimage.distance_transform_edt(omega)
    return np.where(omega, np.ceil(dist - 1e-9), 0).astype(np.int64)


def _offsets(reach: int):
    return sorted(
        (dy * dy + dx * dx, dy, dx)
        for dy in range(-reach, reach + 1)
        for dx in range(-reach, reach + 1)
        if 0 < dy * dy + dx * dx <= reach * reach
    )


def transport(
    data,
    omega,
    runtime,
    *,
    epsilon=5.0,
    kappa=25.0,
    sigma=1.4,
    rho=4.0,
    dtype=np.float32,
    progress=None,
):
    """Coherence transport on (channels, rows, cols) data; returns the filled array."""
    _check(epsilon, kappa, sigma, rho)
    if not omega.any():
        return data.copy()
    if omega.all():
        raise InputError(
            "the mask covers every pixel, so nothing is known to inpaint from; "
            "mark only the damaged region"
        )
    rows, cols = box_around(omega, margin(epsilon, sigma, rho))
    box_omega = omega[rows, cols]
    box = data[:, rows, cols]
    nc, ny, nx = box.shape
    dt = np.dtype(dtype)
    q = runtime.queue
    runtime.check_alloc(box.size * dt.itemsize * 2)

    shell = shells(box_omega)
    flat = np.flatnonzero(box_omega)
    order = np.argsort(shell.reshape(-1)[flat], kind="stable")
    flat = flat[order]
    counts = np.bincount(shell.reshape(-1)[flat])[1:]
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])

    u = cla.to_device(q, np.ascontiguousarray(np.where(box_omega, 0, box), dt))
    known = cla.to_device(q, (~box_omega).astype(dt))
    lst = cla.to_device(q, flat.astype(np.int32))
    h = cla.empty(q, (nc + 1, ny, nx), dt)
    us = cla.empty(q, (nc + 1, ny, nx), dt)  # the last plane: the weights' sums
    t = cla.empty(q, (4, ny, nx), dt)
    prod = cla.empty(q, (4, ny, nx), dt)
    taps_s, taps_r = gaussian_taps(sigma), gaussian_taps(rho)
    buf_s = cla.to_device(q, taps_s.astype(dt))
    buf_r = cla.to_device(q, taps_r.astype(dt))
    rs, rr = np.int32(len(taps_s) // 2), np.int32(len(taps_r) // 2)
    # the channel count is an argument; the define only sizes a private array, rounded up
    # so that grey and colour images (and anything up to 4 channels) share one program
    defines = dict(MAX_CHANNELS=max(4, 1 << (nc - 1).bit_length()))
    k_rows = runtime.kernel("inpainting/coherence.cl", "coherence_smooth_rows", dt, **defines)
    k_cols = runtime.kernel("inpainting/coherence.cl", "coherence_smooth_cols", dt, **defines)
    k_products = runtime.kernel("inpainting/coherence.cl", "coherence_products", dt, **defines)
    k_tensor = runtime.kernel("inpainting/coherence.cl", "coherence_tensor_rows", dt, **defines)
    k_fill = runtime.kernel("inpainting/coherence.cl", "coherence_fill", dt, **defines)
    k_mark = runtime.kernel("inpainting/coherence.cl", "coherence_mark", dt, **defines)
    grid, local, xrun = runtime.grid_launch(nx, ny, 1)
    dims = (np.int32(nx), np.int32(ny))
    run = (*dims, np.int32(xrun))
    for first, count in zip(starts, counts, strict=False):
        if count == 0:
            continue
        k_rows(q, grid, local, u.data, known.data, h.data, buf_s.data, rs, np.int32(nc), *run)
        k_cols(q, grid, local, h.data, us.data, buf_s.data, rs, np.int32(nc), *run)
        k_products(q, grid, local, us.data, known.data, prod.data, np.int32(nc), *run)
        k_tensor(q, grid, local, prod.data, t.data, buf_r.data, rr, *run)
        args = (np.int32(first), np.int32(count))
        # a fixed work-group (Runtime.items): PoCL would compile anew for each shell's count
        launch = runtime.items(int(count))
        k_fill(
            q,
            *launch,
            u.data,
            known.data,
            t.data,
            buf_r.data,
            rr,
            lst.data,
            *args,
            dt.type(epsilon),
            dt.type(kappa),
            np.int32(nc),
            *dims,
        )
        k_mark(q, *launch, known.data, lst.data, *args)
    out = np.array(data, copy=True)
    filled = u.get()
    out[:, rows, cols] = np.where(box_omega, filled, out[:, rows, cols])
    return out


@register(
    "coherence",
    CoherenceOptions,
    margin=lambda omega, o: margin(o.epsilon, o.sigma, o.rho),
)
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    epsilon=CoherenceOptions.epsilon,
    kappa=CoherenceOptions.kappa,
    sigma=CoherenceOptions.sigma,
    rho=CoherenceOptions.rho,
):
    """Registry entry point: coherence transport (see the module docstring)."""
    data = np.asarray(data)
    out = transport(
        data.astype(np.float64, copy=False),
        np.asarray(omega, bool),
        runtime,
        epsilon=epsilon,
        kappa=kappa,
        sigma=sigma,
        rho=rho,
        dtype=dtype,
        progress=progress,
    )
    return out.astype(data.dtype, copy=False)
