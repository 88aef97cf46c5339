"""Explicit flows on implicit surfaces, stepped over the narrow band on the device.

Every step is two kernels: the flow's update over the interpolation nodes (cur -> tmp, the
node band's runs), then the closest-point re-extension of every cell the next step reads
(tmp -> cur, the reach band); the whole extension band is re-extended when a flow returns.
State stays on the device from upload to the final read-back; no host round-trip per step.

This module has the scalar flows (heat, TV, TV denoising, diffusion along a field) and the
driver of the flows_step kernel (`step_flow`), which the harmonic maps (harmonic.py) share.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike

from .._progress import progress_range
from ..errors import InputError
from ..imagedata import check_time_step, positive
from .dynamic_lambda import DynamicLambda
from .storage import make_flow

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
ALL_SIDES = tuple(range(8))


def stability_limit(
    surf: ImplicitSurface, flow: str = "heat", eps: float = 1.0, lam: float = 0.0
) -> float:
    """Largest stable explicit time step of a flow on `surf`; the public form is
    ImplicitSurface.stability_limit, which documents it."""
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


def check_time(t, dt, limit: float, what: str) -> tuple[int, float]:
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
    """Intrinsic heat flow (4.8; 4.7 with weighted=True) of u on `surf` for time t: the
    implementation of ImplicitSurface.heat, which documents the parameters."""
    steps, dt = check_time(t, dt, stability_limit(surf, "heat"), "heat flow")
    flow = make_flow(surf, u, defines={"WEIGHTED": int(bool(weighted))})
    kernel = flow.step_kernel("heat")
    r = surf.grid.scalar(dt / surf.spacing**2)
    for n in progress_range(
        progress, steps, "surface heat", leave=False, queue=surf.grid.runtime.queue
    ):
        flow.step(kernel, ALL_SIDES[n % 8] if alternate else 0, r, channels=flow.nc)
    return flow.result()


def step_flow(
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
    """Shared driver of flows_step: returns (result, info dict)."""
    eps = positive("eps", eps)
    limit = stability_limit(surf, flow_name, eps, float(fidelity or 0.0))
    if sigma is not None and dt is None:
        limit *= 0.5  # room for the dynamic lambda to grow (capped on the device below)
    steps, dt = check_time(t, dt, limit, flow_name)
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
        dynamic = DynamicLambda(
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
        sides = ALL_SIDES[n % 8] if alternate else 0
        if dynamic is not None and n % lambda_every == 0:
            dynamic.update(sides, n // lambda_every)
        flow.step(kernel, sides, dir_dev.data, u0_dev.data, r, g.scalar(dt), lam_dev.data, e2)
    if dynamic is not None:
        info["lambda"] = dynamic.history()
        info["residual_variance"] = dynamic.residual_variance()
    return flow.result(), info


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
    """Intrinsic anisotropic (total variation) flow (4.10): the implementation of
    ImplicitSurface.tv, which documents the parameters."""
    return step_flow(
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
    """TV denoising with a fidelity term (C.1) and dynamic lambda (C.2): the implementation
    of ImplicitSurface.denoise_tv, which documents the parameters."""
    if (sigma is None) == (lam is None):
        raise InputError("give exactly one of sigma (noise level, dynamic lambda) or lam (fixed)")
    if sigma is not None:
        sigma = positive("sigma", sigma)
    fidelity = 0.0 if sigma is not None else float(lam)
    out, info = step_flow(
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
    """Anisotropic diffusion along a tangent field (4.15): the implementation of
    ImplicitSurface.diffuse_along, which documents the parameters."""
    d = np.asarray(direction, dtype=np.float64)
    if d.shape != (3,) + surf.shape:
        raise InputError(f"direction must have shape {(3,) + surf.shape}, got {d.shape}")
    norm = np.sqrt((d**2).sum(axis=0))
    d = np.where(norm > 0, d / np.where(norm > 0, norm, 1), 0)
    return step_flow(
        surf, u, t, dt, "along", p=2, direction=d, alternate=alternate, progress=progress
    )[0]
