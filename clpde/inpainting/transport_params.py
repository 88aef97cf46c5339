"""The options of method="transport", the thesis's scheme (transport.py): TransportOptions,
their defaults and their ranges, checked on construction."""

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
HOLDOUT_WHERE = ("periodic", "all")
GHOST = 2  # ghost layers: the transport stencil reaches two cells


@dataclass(frozen=True)
class TransportOptions:
    """method="transport"'s options (thesis chapter 3), checked on construction.

    Parameters
    ----------
    dt : float
        The time step.
    transport_steps : int
        A, the transport steps of a cycle.
    diffusion_steps : int
        B, the anisotropic diffusion steps of a cycle.
    diffusion_dt : float
        The diffusion's time step (<= 0.25; appendix A's code uses 0.2, the text 0.1).
    epsilon : float
        Width of the band Omega-epsilon around Omega (>= 2 pixels).
    presmooth : int
        Steps of anisotropic diffusion of the box before the loop.
    scaling : {'none', 'quartic-root'}
        Eq. (3.6) as printed, or appendix A's sign(I_t) |I_t|^(1/4) on its 0..255 scale,
        which keeps faint structures moving but never settles (the run then usually ends
        at max_steps).
    rotation : {'ccw', 'cw'}
        The rotation of the gradient (the steady state is the same).
    max_steps : int
        Steps per level at most.
    tol : float
        Stop once the largest change inside Omega over `check_every` cycles is below it
        ([0, 1] units; 0 turns the test off).
    mean_tol : float
        Stop once the mean change there is below it (the test that ends runs on photos,
        where a few pixels never settle; docs/inpainting.md).
    check_every : int
        Cycles of A + B steps between the checks, made on the device.
    fill : {'biharmonic', 'diffusion', 'mean', 'zero'}
        The start inside Omega on the coarsest level (the best PSNR on photos comes early,
        so the start matters; docs/inpainting.md compares them).
    keep_band : bool
        Reset the known pixels of Omega-epsilon after each diffusion batch, or let the
        diffusion keep smoothing them (False).
    stencil : {'isotropic', 'central'}
        Scharr's derivatives, or appendix A's central differences.
    coarse_start : {'corrected', 'upsampled'}
        A finer level's start: the upsampled coarser result plus its mismatch with the
        known border extended into Omega, or the upsampled result alone.
    levels : int, optional
        Resolution levels; None picks them per box from the mask's thickness
        (multiresolution.auto_levels).
    holdout : int
        Width (px) of the ring of known pixels hidden in a second run of the scheme; the
        finest level then stops at the step that filled that ring best, where this comes
        clearly before the stop above (holdout.py). Holes thinner than it, and soft masks,
        keep the stop above; 0 is the thesis's stop everywhere.
    holdout_where : {'periodic', 'all'}
        Which boxes are validated on the hidden ring: 'periodic' (the default) those with a
        cluster of damage in a surround that repeats (the default method's test for the
        exemplar's clusters, pick.periodic_clusters), where the steady state continues the
        pattern with a wrong phase and falls 2-4 dB below its start; every other box keeps
        the thesis's stop. 'all' validates every box deep enough: it gained on the
        calibration half's structure and voids but lost 0.4 dB on the test half's blobs and
        thick holes (docs/inpainting.md, "Stopping on a hidden ring").
    """

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
    levels: int | None = None
    holdout: int = 4  # holdout.WIDTH (not imported: holdout.py imports the device side)
    holdout_where: str = "periodic"  # "all" lost 0.4 dB on the test half's blobs and thick

    def __post_init__(self) -> None:
        _check(self)


# The name the options had before they held the levels and their checks.
InpaintParams = TransportOptions


def _check(p: TransportOptions) -> None:
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
    for name in (
        "transport_steps",
        "diffusion_steps",
        "presmooth",
        "max_steps",
        "check_every",
        "holdout",
    ):
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
    if p.holdout_where not in HOLDOUT_WHERE:
        raise InputError(
            f"holdout_where must be one of {', '.join(HOLDOUT_WHERE)}, not {p.holdout_where!r}"
        )
    if p.fill not in FILLS:
        raise InputError(f"fill must be one of {', '.join(FILLS)}, not {p.fill!r}")

    levels = p.levels
    if levels is not None and (
        isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 1
    ):
        raise InputError(f"levels must be an integer >= 1 or None (automatic), not {levels!r}")
