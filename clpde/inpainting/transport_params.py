"""The options of method="transport", the thesis's scheme (transport.py): their defaults
(InpaintParams, as `clpde.inpaint` names them), their ranges (check_params) and the
dispatch's conversion of a call's keywords (transport_params)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..imagedata import positive

SCALINGS = ("none", "quartic-root")
ROTATIONS = ("ccw", "cw")
FILLS = ("diffusion", "biharmonic", "mean", "zero")
STENCILS = ("central", "isotropic")
COARSE_STARTS = ("corrected", "upsampled")
GHOST = 2  # ghost layers: the transport stencil reaches two cells


@dataclass(frozen=True)
class InpaintParams:
    dt: float = 0.1
    transport_steps: int = 15  # A
    diffusion_steps: int = 2  # B
    diffusion_dt: float = 0.1  # the thesis' speed; appendix A's code uses 0.2
    epsilon: float = 3.0
    presmooth: int = 1
    scaling: str = "none"
    rotation: str = "ccw"
    max_steps: int = 3000
    tol: float = 1e-4  # on the largest change in Omega over a check interval
    mean_tol: float = 4e-4  # on the mean change in Omega over a check interval
    check_every: int = 2  # cycles of A + B steps
    fill: str = "biharmonic"
    keep_band: bool = True
    stencil: str = "isotropic"
    coarse_start: str = "corrected"


def check_params(p: InpaintParams) -> None:
    """InputError for an option of the scheme out of its range."""
    positive("dt", p.dt)
    positive("diffusion_dt", p.diffusion_dt)
    if p.diffusion_dt > 0.25:
        raise InputError(
            f"diffusion_dt={p.diffusion_dt:g} is beyond the stability limit 0.25 of the explicit "
            "curvature diffusion; use diffusion_dt <= 0.25"
        )
    if p.epsilon < 2:
        raise InputError(
            f"epsilon={p.epsilon:g} is too small: the transport stencil reaches two pixels past "
            "Omega, so epsilon must be at least 2"
        )
    for name in ("transport_steps", "diffusion_steps", "presmooth", "max_steps", "check_every"):
        v = getattr(p, name)
        low = 1 if name in ("transport_steps", "check_every") else 0
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
            raise InputError(f"{name} must be an integer >= {low}, not {v!r}")
    for name in ("tol", "mean_tol"):
        v = getattr(p, name)
        if not np.isfinite(v) or v < 0:
            raise InputError(f"{name} must be a number >= 0, not {v}")
    if p.scaling not in SCALINGS:
        raise InputError(f"scaling must be one of {', '.join(SCALINGS)}, not {p.scaling!r}")
    if p.rotation not in ROTATIONS:
        raise InputError(f"rotation must be 'ccw' or 'cw', not {p.rotation!r}")
    if p.coarse_start not in COARSE_STARTS:
        raise InputError(
            f"coarse_start must be one of {', '.join(COARSE_STARTS)}, not {p.coarse_start!r}"
        )
    if p.stencil not in STENCILS:
        raise InputError(f"stencil must be one of {', '.join(STENCILS)}, not {p.stencil!r}")
    if p.fill not in FILLS:
        raise InputError(f"fill must be one of {', '.join(FILLS)}, not {p.fill!r}")


# InpaintParams' fields that `inpaint` names in its signature (the others go in **options),
# in the fields' order
_TRANSPORT_ARGS = (
    "dt",
    "transport_steps",
    "diffusion_steps",
    "diffusion_dt",
    "epsilon",
    "presmooth",
    "scaling",
    "rotation",
    "max_steps",
    "tol",
    "mean_tol",
    "check_every",
    "fill",
    "keep_band",
)


def transport_params(params: dict) -> InpaintParams:
    unknown = set(params) - set(InpaintParams.__dataclass_fields__)
    if unknown:
        raise InputError(f"unknown inpainting option(s): {', '.join(sorted(unknown))}")
    return InpaintParams(**params)
