"""Explicit flows on implicit surfaces, stepped over the narrow band on the device.

Every step is two kernels: the flow's update over the interpolation nodes (cur -> tmp, the
node band's runs), then the closest-point re-extension of every cell the next step reads
(tmp -> cur, the reach band); the whole extension band is re-extended when a flow returns.
State stays on the device from upload to the final read-back; no host round-trip per step.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike

from .._progress import progress_range
from ..errors import InputError
from ..imagedata import check_time_step, positive
from .band import make_flow

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/flows.cl", "surface/shape.cl")

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


@dataclass
class SurfaceDenoiseInfo:
    """What a surface denoise_tv run did (the surface's counterpart of clpde.DenoiseInfo).

    Parameters
    ----------
    steps : int
        Time steps run.
    dt : float
        Their length.
    lam_history : list of float, optional
        The dynamic lambda after each of its updates (every 10 steps; None for a fixed lam).
    residual_variance : float, optional
        Mean (u - u0)^2 over the surface (None for a fixed lam).
    """

    steps: int
    dt: float
    lam_history: list[float] | None = None
    residual_variance: float | None = None

    @property
    def lam(self) -> float | None:
        """The final lambda (None for a fixed lam)."""
        return self.lam_history[-1] if self.lam_history else None


# One-sided difference choices per axis: bit set = backward gradient (forward divergence).
_ALL_SIDES = tuple(range(8))


def stability_limit(
    surf: ImplicitSurface, flow: str = "heat", eps: float = 1.0, lam: float = 0.0
) -> float:
    """Largest stable explicit time step (world time units) of a flow on `surf`.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface (its grid spacing sets the limit).
    flow : {'heat', 'tv', 'harmonic2', 'harmonic1', 'along'}
        The flow.
    eps : float, optional
        The regularisation of |grad u| of 'tv' and 'harmonic1'.
    lam : float, optional
        The fidelity weight of a TV denoising step.

    Returns
    -------
    float
        The largest stable dt.

    Raises
    ------
    InputError
        For an unknown flow.

    Examples
    --------
    >>> from clpde.surface import ImplicitSurface, stability_limit
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> round(stability_limit(s, "heat"), 6)
    0.001667
    """
    h2 = surf.spacing**2
    if flow in ("heat", "harmonic2", "along"):
        # |N| P_N has norm <= |N| and the one-sided div is minus the transpose of the
        # one-sided grad: the operator's spectrum lies in [-12/h^2, 0] for a distance
        # function, as for the 7-point Laplacian (|d| <= 1 for the flux along d).
        return h2 / 6.0
    if flow in ("tv", "harmonic1"):
        # the flux gain 1/|P grad u|_eps is at most 1/eps
        return h2 * eps / 6.0 / (1 + h2 * eps * lam / 6.0)
    raise InputError(f"unknown surface flow {flow!r}; use heat, tv, harmonic2, harmonic1 or along")


def _check_time(t, dt, limit: float, what: str) -> tuple[int, float]:
    """(steps, dt) covering time t; an explicit unstable dt is an error naming the limit."""
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise InputError(f"t must be a non-negative number, not {t!r}") from None
    if not math.isfinite(t) or t < 0:
        raise InputError(f"t must be a non-negative number, not {t!r}")
    if dt is None:
        steps = max(1, math.ceil(t / limit - 1e-9))
        return steps, t / steps
    dt = check_time_step(dt, limit, what)
    steps = max(1, math.ceil(t / dt - 1e-9))
    return steps, t / steps


def heat(
    surf: ImplicitSurface,
    u: ArrayLike,
    t: float,
    dt: float | None = None,
    *,
    weighted: bool = False,
    alternate: bool = True,
    progress: bool | None = None,
) -> np.ndarray:
    """Intrinsic heat flow on `surf` for time t: eq. (4.8), or (4.7) with weighted=True.

    Appendix E's scheme (one-sided gradient, projection on the tangent plane with N from
    central differences of psi, the complementary one-sided divergence), explicit Euler
    steps, whole-band closest-point re-extension after each step.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.
    u : array_like
        Data on the surface: dense (the grid's shape, or (channels,) + it) or in band form
        (`surf.band_indices()`); returned in kind.
    t : float
        The evolution time (world units).
    dt : float, optional
        The time step; 0.8 of `stability_limit` by default, never beyond it.
    weighted : bool, optional
        Eq. (4.7), the flux weighted by |grad psi|, instead of (4.8).
    alternate : bool, optional
        Cycle the step through the eight forward/backward combinations, as appendix E
        suggests (smaller errors, docs/surface.md); False keeps forward gradient / backward
        divergence throughout.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.

    Returns
    -------
    ndarray
        u after time t, in u's form and float dtype.

    Raises
    ------
    InputError
        For data of another shape, non-finite values in the band or an unstable dt.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, heat
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> u = s.field(lambda x, y, z: z)
    >>> smooth = heat(s, u, 0.05)
    >>> smooth.shape == u.shape, smooth.dtype
    (True, dtype('float64'))
    """
    steps, dt = _check_time(t, dt, stability_limit(surf, "heat"), "heat flow")
    flow = make_flow(surf, u, defines={"WEIGHTED": int(bool(weighted))})
    kernel = flow.step_kernel("heat")
    r = surf.grid.scalar(dt / surf.spacing**2)
    for n in progress_range(
        progress, steps, "surface heat", leave=False, queue=surf.grid.runtime.queue
    ):
        flow.step(kernel, _ALL_SIDES[n % 8] if alternate else 0, r, channels=flow.nc)
    return flow.result()


def _run(
    surf,
    u,
    t,
    dt,
    flow_name,
    *,
    p=2,
    eps=1.0,
    harmonic=False,
    direction=None,
    fidelity=None,
    sigma=None,
    weighted=False,
    alternate=True,
    progress=None,
    lambda_every=10,
    line_field=False,
    correct_lambda=True,
):
    """Shared driver of flow_step: returns (result, info dict)."""
    eps = positive("eps", eps)
    limit = stability_limit(surf, flow_name, eps, float(fidelity or 0.0))
    if sigma is not None and dt is None:
        limit *= 0.5  # room for the dynamic lambda to grow (capped on the device below)
    steps, dt = _check_time(t, dt, limit, flow_name)
    defines = {
        "FLOW_P": p,
        "HARMONIC": int(harmonic),
        "FIDELITY": int(fidelity is not None),
        "ALONG": int(direction is not None),
        "WEIGHTED": int(bool(weighted)),
        "LINE_FIELD": int(bool(line_field)),
    }
    flow = make_flow(surf, u, normalize=harmonic, line_field=line_field, defines=defines)
    g, q, h = surf.grid, surf.runtime.queue, surf.spacing
    kernel = flow.step_kernel("flow")
    r = g.scalar(dt / h**p)
    e2 = g.scalar((h * eps) ** 2)
    dir_dev = flow.fixed(direction, halo=2) if direction is not None else flow.psi
    u0_dev = flow.cur.copy() if fidelity is not None else flow.psi
    info = {"steps": steps, "dt": dt}
    lam_dev = cla.to_device(q, np.array([fidelity or 0.0], g.dtype))
    dynamic = None
    if sigma is not None:
        # lambda may grow to where dt is at the stability limit, no further
        lam_max = max(0.0, 1 / dt - 6 / (h**2 * eps))
        dynamic = _DynamicLambda(
            surf,
            flow,
            u0_dev,
            lam_dev,
            eps,
            sigma,
            lam_max,
            updates=-(-steps // lambda_every),
            correct=correct_lambda,
        )
    for n in progress_range(
        progress, steps, f"surface {flow_name}", leave=False, queue=surf.grid.runtime.queue
    ):
        sides = _ALL_SIDES[n % 8] if alternate else 0
        if dynamic is not None and n % lambda_every == 0:
            dynamic.update(sides, n // lambda_every)
        flow.step(kernel, sides, dir_dev.data, u0_dev.data, r, g.scalar(dt), lam_dev.data, e2)
    if dynamic is not None:
        info["lambda"] = dynamic.history()
        info["residual_variance"] = dynamic.residual_variance()
    return flow.result(), info


class _DynamicLambda:
    """lambda of (C.2) kept on the device: each update enqueues the surface integrals' per-cell
    terms (the flow's lambda_terms, in its storage), their chunk sums and the new lambda
    (tv_lambda_update), with no read-back; the history of lambda comes back once, at the end.
    Its kernels come with the flow's defines (they read none of them): on the lists, no
    build of their own."""

    CHUNK = 2048

    def __init__(self, surf, flow, u0_dev, lam_dev, eps, sigma, lam_max, updates, correct=True):
        g, q = surf.grid, surf.runtime.queue
        self.defines = flow.defines
        self.surf, self.flow, self.u0, self.lam, self.eps = surf, flow, u0_dev, lam_dev, eps
        self.sigma, self.lam_max, self.correct = sigma, lam_max, correct
        self.n = flow.terms_size
        # zeros: the bricks' terms are written at the nodes only
        self.terms = [cla.zeros(q, self.n, g.dtype) for _ in range(3)]
        self.groups = max(1, -(-self.n // self.CHUNK))
        self.partials = [cla.empty(q, self.groups, g.dtype) for _ in range(3)]
        self.slots = cla.zeros(q, max(updates, 1), g.dtype)
        self.capped = cla.zeros(q, 1, np.int32)
        self.state = cla.to_device(q, np.ones(1, g.dtype))  # the correction factor f
        self._chunk_sum = g.kernel("surface/flows.cl", "chunk_sum", **self.defines)
        self._update = g.kernel("surface/flows.cl", "tv_lambda_update", **self.defines)

    def _sums(self, sides: int) -> None:
        s = self.surf
        q = s.runtime.queue
        self.flow.lambda_terms(self.u0, self.terms, sides, self.eps)
        for a, partial in zip(self.terms, self.partials, strict=True):
            self._chunk_sum(
                q,
                *s.runtime.items(self.groups),
                a.data,
                np.int32(self.n),
                np.int32(self.CHUNK),
                partial.data,
            )

    def update(self, sides: int, slot: int) -> None:
        s = self.surf
        g, q = s.grid, s.runtime.queue
        self._sums(sides)
        self._update(
            q,
            (1,),
            (1,),
            *(p.data for p in self.partials),
            np.int32(self.groups),
            g.scalar(1 / (s.spacing * self.sigma**2)),
            g.scalar(self.correct / self.sigma**2),
            g.scalar(self.lam_max),
            self.lam.data,
            self.state.data,
            self.slots.data,
            np.int32(slot),
            self.capped.data,
        )

    def history(self) -> list[float]:
        if self.capped.get()[0]:
            warnings.warn(
                f"the dynamic lambda was capped at {self.lam_max:g}, the largest this time step "
                "keeps stable; pass a smaller dt (or leave dt=None) to let it grow further",
                stacklevel=4,
            )
        return [float(v) for v in self.slots.get()]

    def residual_variance(self) -> float:
        """Mean of (u - u0)^2 over the surface (smeared-delta quadrature) for the flow's
        current state (forward differences)."""
        self._sums(0)
        _, area, resid = (float(p.get().astype(np.float64).sum()) for p in self.partials)
        return resid / area


def tv(
    surf: ImplicitSurface,
    u: ArrayLike,
    t: float,
    dt: float | None = None,
    *,
    eps: float = 1.0,
    weighted: bool = False,
    alternate: bool = True,
    progress: bool | None = None,
) -> np.ndarray:
    """Intrinsic anisotropic (total variation) flow (4.10) for time t.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.
    u : array_like
        Data on the surface, dense or in band form (as for `heat`); returned in kind.
    t : float
        The evolution time.
    dt : float, optional
        The time step; 0.8 of `stability_limit` by default.
    eps : float, optional
        Regularisation of |P grad u| (world gradient units), so that the explicit step stays
        bounded (dt <= h^2 eps / 6).
    weighted : bool, optional
        The flux weighted by |grad psi|, as for `heat`.
    alternate : bool, optional
        Cycle the one-sided differences, as for `heat`.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.

    Returns
    -------
    ndarray
        u after time t, in u's form.

    Raises
    ------
    InputError
        For data of another shape, non-finite values in the band or an unstable dt.

    Examples
    --------
    >>> from clpde.surface import ImplicitSurface, tv
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> tv(s, s.field(lambda x, y, z: z), 0.01).shape == s.shape
    True
    """
    return _run(
        surf,
        u,
        t,
        dt,
        "tv",
        p=1,
        eps=eps,
        weighted=weighted,
        alternate=alternate,
        progress=progress,
    )[0]


def denoise_tv(
    surf: ImplicitSurface,
    u: ArrayLike,
    sigma: float | None = None,
    t: float = 1.0,
    dt: float | None = None,
    *,
    lam: float | None = None,
    eps: float = 1.0,
    alternate: bool = True,
    correct_lambda: bool = True,
    progress: bool | None = None,
    return_info: bool = False,
) -> np.ndarray | tuple[np.ndarray, SurfaceDenoiseInfo]:
    """TV denoising on the surface with a fidelity term (C.1).

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.
    u : array_like
        Noisy data on the surface, dense or in band form (as for `heat`).
    sigma : float, optional
        The noise level, for the dynamic lambda of (C.2): updated on the device every 10
        steps, never read back while stepping, capped (with a warning) where it would make
        dt unstable. Give it or `lam`.
    t : float, optional
        The evolution time.
    dt : float, optional
        The time step; 0.8 of `stability_limit` by default.
    lam : float, optional
        A fixed fidelity weight instead of `sigma`.
    eps : float, optional
        Regularisation of |P grad u|, as for `tv`.
    alternate : bool, optional
        Cycle the one-sided differences, as for `heat`.
    correct_lambda : bool, optional
        Scale the dynamic lambda by a factor that moves until the residual variance is
        sigma^2, the constraint (C.2) comes from (the discrete (C.2) alone settles above it,
        docs/surface.md); False is the plain formula (kernels/surface/flows.cl,
        tv_lambda_update).
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    return_info : bool, optional
        Also return a SurfaceDenoiseInfo: steps, dt, the lambda history and the residual
        variance (mean of (u - u0)^2 over the surface).

    Returns
    -------
    ndarray or (ndarray, SurfaceDenoiseInfo)
        The denoised data in u's form (and the info with return_info).

    Raises
    ------
    InputError
        Unless exactly one of sigma and lam is given; for data that cannot be used.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, denoise_tv
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> noisy = s.field(lambda x, y, z: z) + 0.1 * np.random.default_rng(0).normal(size=s.shape)
    >>> clean, info = denoise_tv(s, noisy, sigma=0.1, t=0.01, return_info=True)
    >>> clean.shape == s.shape, info.steps > 0
    (True, True)
    """
    if (sigma is None) == (lam is None):
        raise InputError("give exactly one of sigma (noise level, dynamic lambda) or lam (fixed)")
    if sigma is not None:
        sigma = positive("sigma", sigma)
    fidelity = 0.0 if sigma is not None else float(lam)
    out, info = _run(
        surf,
        u,
        t,
        dt,
        "tv",
        p=1,
        eps=eps,
        fidelity=fidelity,
        sigma=sigma,
        alternate=alternate,
        progress=progress,
        correct_lambda=correct_lambda,
    )
    if not return_info:
        return out
    return out, SurfaceDenoiseInfo(
        info["steps"], info["dt"], info.get("lambda"), info.get("residual_variance")
    )


def harmonic_map(
    surf: ImplicitSurface,
    u: ArrayLike,
    t: float,
    p: int = 2,
    dt: float | None = None,
    *,
    eps: float = 1.0,
    alternate: bool = True,
    progress: bool | None = None,
    line_field: bool = False,
) -> np.ndarray:
    """Harmonic map flow of unit vectors on the surface, (D.7) for p = 2 and (4.11) for
    p = 1, renormalised after every step. u: (channels, nz, ny, nx).

    line_field=True treats u as a field of lines, u and -u alike (principal directions,
    Figure 4.5): before a step or an interpolation weighs neighbouring vectors, each is
    turned to the side of the vector it is compared with, so arbitrary sign flips between
    neighbours are neither smoothed into zero vectors nor counted as edges. This is the
    harmonic map into the projective plane, worked in local sign-aligned charts; the doubled-
    angle alternative needs a tangent frame, which has no smooth global choice on a sphere.
    The result's signs are arbitrary (consistent only locally)."""
    if p not in (1, 2):
        raise InputError(f"p must be 1 or 2, not {p!r}")
    data = np.asarray(u, dtype=np.float64)
    band_form = data.ndim == 2 and surf.band.form_channels(data) is not None
    if data.ndim != 4 and not band_form:
        raise InputError(
            "harmonic maps need vector data (channels, nz, ny, nx), or its band "
            f"form (channels, {surf.ext_band.n}), got shape {data.shape}"
        )
    norm = np.sqrt((data**2).sum(axis=0))
    norm = norm if band_form else norm[np.abs(surf.psi) < surf.outer * surf.spacing]
    if np.any(norm == 0):
        raise InputError("u has zero vectors in the band; harmonic maps need unit vectors")
    if np.abs(norm - 1).max() > 1e-3:
        warnings.warn("u is not made of unit vectors; normalising it", stacklevel=2)
    return _run(
        surf,
        u,
        t,
        dt,
        f"harmonic{p}",
        p=p,
        eps=eps,
        harmonic=True,
        alternate=alternate,
        progress=progress,
        line_field=line_field,
    )[0]


def denoise_colour(
    surf: ImplicitSurface,
    rgb: ArrayLike,
    t: float,
    dt: float | None = None,
    *,
    brightness: str = "tv",
    p: int = 1,
    eps: float = 1.0,
    alternate: bool = True,
    progress: bool | None = None,
) -> np.ndarray:
    """Colour data on the surface denoised as in Figure 4.6: the chroma (the RGB vector over
    its length, a unit vector) by the harmonic map flow of exponent p (4.11 for p = 1), the
    brightness (the length) separately by a scalar flow, "tv" (4.10, the default: it keeps
    edges of brightness that heat blurs), "heat" (4.8) or None (kept), both for time t.
    rgb: (3, nz, ny, nx), non-negative (e.g. colours in [0, 1]). Cells with no colour
    (black) take the grey chroma, so they carry no direction."""
    data = np.asarray(rgb)
    if data.shape != (3,) + surf.shape:
        raise InputError(
            f"rgb must have shape {(3,) + surf.shape} (channels first), got {data.shape}"
        )
    if brightness not in ("heat", "tv", None):
        raise InputError(f"brightness must be 'heat', 'tv' or None, not {brightness!r}")
    values = data.astype(np.float64)
    band = np.abs(surf.psi) < surf.outer * surf.spacing
    if not np.all(np.isfinite(values[:, band])):
        raise InputError("rgb has NaN or infinite values on the surface's band")
    if np.any(values[:, band] < 0):
        raise InputError(
            "rgb has negative values on the band; give colours as non-negative "
            "intensities (e.g. RGB in [0, 1])"
        )
    length = np.sqrt((values**2).sum(axis=0))
    lit = length > 1e-6 * max(float(length[band].max()), 1e-300)
    chroma = np.where(lit, values / np.where(lit, length, 1), 1 / np.sqrt(3.0))
    chroma = harmonic_map(surf, chroma, t, p, dt, eps=eps, alternate=alternate, progress=progress)
    if brightness == "heat":
        length = heat(surf, length, t, dt, alternate=alternate, progress=progress)
    elif brightness == "tv":
        length = tv(surf, length, t, dt, eps=eps, alternate=alternate, progress=progress)
    out = chroma * length
    return out.astype(data.dtype if np.issubdtype(data.dtype, np.floating) else np.float64)


def diffuse_along(
    surf: ImplicitSurface,
    u: ArrayLike,
    direction: ArrayLike,
    t: float,
    dt: float | None = None,
    *,
    alternate: bool = True,
    progress: bool | None = None,
) -> np.ndarray:
    """Anisotropic diffusion along a tangent field d (4.15): flow visualisation of d when u is
    noise. direction: (3, nz, ny, nx), normalised here."""
    d = np.asarray(direction, dtype=np.float64)
    if d.shape != (3,) + surf.shape:
        raise InputError(f"direction must have shape {(3,) + surf.shape}, got {d.shape}")
    norm = np.sqrt((d**2).sum(axis=0))
    d = np.where(norm > 0, d / np.where(norm > 0, norm, 1), 0)
    return _run(surf, u, t, dt, "along", p=2, direction=d, alternate=alternate, progress=progress)[
        0
    ]


def principal_directions(
    surf: ImplicitSurface,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Principal curvature directions and curvatures of the surface, extended along normals.

    Directions are defined up to sign, which the flows along them ignore (the flux (d.Pv)d is
    even in d); sample them at nodes rather than interpolating across sign flips.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.

    Returns
    -------
    major, minor : ndarray
        (3, nz, ny, nx) unit tangent fields (major = the larger curvature), computed at every
        cell of the extension band (constant along normals for a distance function); zeros
        off the band.
    curvatures : ndarray
        (2, nz, ny, nx): the larger and the smaller principal curvature.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, principal_directions
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> major, minor, curvatures = principal_directions(s)
    >>> on = np.abs(s.psi) < 0.05
    >>> bool(np.allclose(curvatures[:, on], 1.0, atol=0.1))   # a unit sphere: k1 = k2 = 1
    True
    """
    g, q = surf.grid, surf.runtime.queue
    band = surf.ext_band
    n = max(band.n, 1)
    dirs = cla.empty(q, (6, n), g.dtype)
    curv = cla.empty(q, (2, n), g.dtype)
    g.launch_list(
        g.kernel("surface/shape.cl", "principal_directions"),
        band,
        surf.psi_dev.data,
        g.scalar(1 / surf.spacing),
        dirs.data,
        curv.data,
        *g.strides(),
    )
    idx = band.indices.get()[: band.n]
    vol = np.zeros((8, g.volume))
    vol[:6, idx] = dirs.get()[:, : band.n]
    vol[6:, idx] = curv.get()[:, : band.n]
    vol = g.interior(vol.reshape((8,) + g.padded_shape))
    return vol[0:3].copy(), vol[3:6].copy(), vol[6:8].copy()


TURK = {"da": 1 / 8, "db": 1 / 32, "s": 0.2 / 16, "beta": 12.0, "beta_spread": 0.1, "start": 4.0}
THESIS_FIG_4_7 = {
    "da": 1.0,
    "db": 0.0625,
    "s": 0.025,
    "beta": 12.0,
    "beta_spread": 0.1,
    "start": 4.0,
}


def reaction_diffusion(
    surf: ImplicitSurface,
    iterations: int,
    *,
    direction: ArrayLike | None = None,
    dt: float | None = None,
    seed: int = 0,
    params: dict | None = None,
    alternate: bool = True,
    progress: bool | None = None,
    state: ArrayLike | None = None,
) -> np.ndarray:
    """Turk's two-chemical reaction-diffusion on the surface (4.12, 4.13; 4.14 with a tangent
    field `direction`), in grid units as Turk's own code: dt per iteration, diffusion rates
    in cells^2 per unit time, so patterns have the same size in cells on any surface.
    Defaults: Figure 4.7's numbers (THESIS_FIG_4_7: D1 = 1, D2 = 1/16, s = 0.025, a pattern
    of about 12 cells, dt = 0.15); TURK gives Turk's own rates (1/8, 1/32, s = 0.2/16, dt = 1,
    spots of about 10 cells). Turk's rates sit at the edge of the Turing instability (the
    fastest mode's growth rate is 0 at beta = 12): only the random spread of beta grows a
    pattern, and the anisotropic flow (4.14) along a tube's short circles, where few
    wavelengths fit, stays flat. Figure 4.7's numbers are unstable over 10-30 cells.
    dt (None: 0.9 times the stability limit, at most 1) is in grid time units.
    Returns the (2, nz, ny, nx) chemicals (a, b); pass them back as `state` to continue."""
    p = dict(THESIS_FIG_4_7 if params is None else params)
    limit = 1.0 / (6.0 * max(p["da"], p["db"]))
    what = f"reaction-diffusion (diffusion rate {max(p['da'], p['db']):g})"
    dt = min(1.0, 0.9 * limit) if dt is None else check_time_step(dt, limit, what)
    rng = np.random.default_rng(seed)
    beta = p["beta"] + p["beta_spread"] * rng.uniform(-1, 1, surf.shape)
    start = (
        np.full((2,) + surf.shape, p["start"]) if state is None else np.asarray(state, np.float64)
    )
    direction_field = None
    if direction is not None:
        d = np.asarray(direction, dtype=np.float64)
        if d.shape != (3,) + surf.shape:
            raise InputError(f"direction must have shape {(3,) + surf.shape}, got {d.shape}")
        norm = np.sqrt((d**2).sum(axis=0))
        direction_field = d / np.where(norm > 0, norm, 1)
    flow = make_flow(surf, start, defines={"ALONG": int(direction is not None)})
    g = surf.grid
    beta_dev = flow.fixed(beta[None])
    dir_dev = flow.psi if direction_field is None else flow.fixed(direction_field, halo=2)
    kernel = flow.step_kernel("turk")
    for n in progress_range(
        progress, int(iterations), "reaction-diffusion", leave=False, queue=surf.grid.runtime.queue
    ):
        flow.step(
            kernel,
            _ALL_SIDES[n % 8] if alternate else 0,
            dir_dev.data,
            beta_dev.data,
            g.scalar(dt),
            g.scalar(p["da"]),
            g.scalar(p["db"]),
            g.scalar(p["s"]),
        )
    return flow.result()


def turk_linear_wavelength(params: dict | None = None) -> float:
    """Wavelength (cells) of the fastest-growing mode of Turk's system linearised about its
    uniform state b = 16 - beta, a = 16 / b (planar linear stability analysis, grid units)."""
    p = dict(TURK if params is None else params)
    s, beta = p["s"], p["beta"]
    b = 16.0 - beta  # a b = 16 and a b - b - beta = 0
    a = 16.0 / b
    k = np.linspace(1e-3, np.pi, 20000)  # wavenumber, radians per cell
    k2 = k**2
    # Jacobian [[-s b - Da k^2, -s a], [s b, s (a - 1) - Db k^2]]
    j11 = -s * b - p["da"] * k2
    j12 = -s * a
    j21 = s * b
    j22 = s * (a - 1) - p["db"] * k2
    tr, det = j11 + j22, j11 * j22 - j12 * j21
    growth = 0.5 * tr + np.sqrt(np.maximum(0.25 * tr**2 - det, 0))
    return float(2 * np.pi / k[np.argmax(growth)])
