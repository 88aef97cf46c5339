"""method="spectral"'s options: their defaults and their ranges (spectral.py has the method
and `fill`'s docstring their meaning)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..imagedata import InputError
from .spectral_plan import MAXL

MAXK = 512  # kernels/inpainting/spectral.cl's SPECTRAL_MAXK
COLOURS = ("pca", "channels")


@dataclass(frozen=True)
class SpectralOptions:
    """method="spectral"'s options (solve's docstring has their meaning), checked on
    construction."""

    block: int = 8
    min_block: int = 4
    border: int = 12
    split: float = 0.3
    rho: float = 0.6
    delta: float = 1.0
    gamma: float = 0.7
    alpha: float = 2.0
    iterations: int = 100
    stop: float = 0.0
    floor: float = 0.0
    stall: float = 0.005
    colour: str = "pca"
    detrend: bool = True
    shifts: int = 2
    cutoff: float = 1.5
    per_pixel: float = 0.0
    thin_border: int = 6
    minor: float = 0.3

    def __post_init__(self) -> None:
        check(
            self.block,
            self.min_block,
            self.border,
            self.split,
            self.rho,
            self.delta,
            self.gamma,
            self.alpha,
            self.iterations,
            self.stop,
            self.floor,
            self.colour,
            self.cutoff,
            self.per_pixel,
            self.shifts,
            self.thin_border,
            self.minor,
            self.stall,
        )


def check(
    block,
    min_block,
    border,
    split,
    rho,
    delta,
    gamma,
    alpha,
    iterations,
    stop,
    floor,
    colour,
    cutoff,
    per_pixel,
    shifts,
    thin_border=0,
    minor=1.0,
    stall=0.0,
):
    """InputError for an option of `fill` out of its range."""
    for name, v in (
        ("block", block),
        ("min_block", min_block),
        ("border", border),
        ("iterations", iterations),
    ):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise InputError(f"{name} must be an integer >= 1, not {v!r}")
    if block % 2 or min_block % 2:
        raise InputError(
            f"block and min_block must be even (the window's centre), not {block} and {min_block}"
        )
    if min_block > block or block % min_block or (block // min_block) & (block // min_block - 1):
        raise InputError(
            f"min_block={min_block} must be block={block} halved zero or more "
            "times (blocks are split in four)"
        )
    if block + 2 * border > MAXL:
        raise InputError(
            f"block + 2 * border = {block + 2 * border} exceeds the largest window "
            f"{MAXL}; use a smaller block or border"
        )
    if iterations > MAXK:
        raise InputError(f"iterations={iterations} exceeds {MAXK}; use fewer")
    for name, v, lo, hi in (
        ("rho", rho, 0.0, 1.0),
        ("delta", delta, 0.0, 1.0),
        ("gamma", gamma, 0.0, 1.0),
        ("split", split, 0.0, 1.0),
        ("minor", minor, 0.0, 1.0),
    ):
        if not (np.isfinite(v) and lo <= v <= hi) or (name in ("rho", "gamma", "minor") and v == 0):
            raise InputError(f"{name} must be a number in ({lo:g}, {hi:g}], not {v!r}")
    if not (np.isfinite(alpha) and alpha >= 0):
        raise InputError(f"alpha must be a number >= 0, not {alpha!r}")
    if not (np.isfinite(stop) and 0 <= stop < 1):
        raise InputError(f"stop must be a number in [0, 1), not {stop!r}")
    if not (np.isfinite(stall) and 0 <= stall < 1):
        raise InputError(f"stall must be a number in [0, 1), not {stall!r}")
    if not (np.isfinite(floor) and floor >= 0):
        raise InputError(f"floor must be a number >= 0 (a residual's RMS), not {floor!r}")
    if colour not in COLOURS:
        raise InputError(f"colour must be one of {', '.join(COLOURS)}, not {colour!r}")
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise InputError(
            f"cutoff must be a number > 0 (a share of the Nyquist frequency), not {cutoff!r}"
        )
    if not (np.isfinite(per_pixel) and per_pixel >= 0):
        raise InputError(f"per_pixel must be a number >= 0, not {per_pixel!r}")
    if (
        isinstance(thin_border, bool)
        or not isinstance(thin_border, (int, np.integer))
        or thin_border < 0
    ):
        raise InputError(f"thin_border must be an integer >= 0 (0: off), not {thin_border!r}")
    if shifts not in (1, 2, 4):
        raise InputError(f"shifts must be 1, 2 or 4 (block grids averaged), not {shifts!r}")
