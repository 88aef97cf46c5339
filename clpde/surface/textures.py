"""Reaction-diffusion textures on a surface: Turk's two chemicals (4.12-4.14), stepped on the
band like the flows."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._progress import progress_range
from ..errors import InputError
from ..imagedata import check_time_step
from .flows import ALL_SIDES
from .storage import make_flow

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


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
    """Turk's two-chemical reaction-diffusion (4.12-4.14) on `surf`: the implementation
    of ImplicitSurface.reaction_diffusion, which documents the parameters."""
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
            ALL_SIDES[n % 8] if alternate else 0,
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
