"""What an inpainting run yields and reports, for every method alike: InpaintState (one
intermediate state, what `Inpainting.iterate` yields), InpaintInfo (what the run did), and
SolveRun, which runs a method without states of its own as one step."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._progress import State


@dataclass
class InpaintState(State):
    """One intermediate state: the whole image (in the input's layout and dtype)."""

    level: int  # 0 is the finest
    step: int  # steps taken on this level so far
    image: np.ndarray
    change: float | None = None  # largest change in Omega over the last check interval

    @property
    def time(self) -> None:
        """None: inpainting mixes transport and diffusion steps, it has no single time."""
        return None


@dataclass
class InpaintInfo:
    """What a run did. `steps` counts transport plus diffusion steps on the finest level."""

    steps: int
    converged: bool
    levels: int
    steps_per_level: list = field(default_factory=list)  # fine to coarse
    omega_pixels: int = 0
    band_pixels: int = 0
    seconds: float = 0.0  # the run's time, its programs' first builds left out
    build_seconds: float = 0.0  # spent building OpenCL programs during the run (first use)
    snapshots: list = field(default_factory=list)
    method: str | None = "transport"  # None: the mask was empty, nothing was run
    # method="auto": the method its votes chose most (by pixels), else the method itself
    chosen: str | None = None
    boxes: list = field(default_factory=list)  # (y0, y1, x0, x1) of each box solved
    box_methods: list = field(default_factory=list)  # the method that solved each box
    # omega pixels of each box that the exemplar filled (under method="auto" a box named
    # "<structure>+exemplar" had only its thick parts refilled by the exemplar)
    box_exemplar_pixels: list = field(default_factory=list)
    # method="auto": per box, what the self-validation chose for each cluster of damage, and
    # why (inpainting/auto.py's report)
    choices: list = field(default_factory=list)


class SolveRun:
    """A method without states of its own, run by its `solve` as one step: the interface
    of the methods' runs (`states(every)`, then `solution` and the counters). For a method
    without soft_mask, a soft mask is applied afterwards, as m * filled + (1 - m) * observed."""

    steps, converged, levels, steps_per_level, band_pixels = 0, True, 1, [], 0

    def __init__(
        self, method, data, omega, runtime, options, damage, fidelity, dtype, progress, seed
    ):
        self.method, self.data, self.omega, self.runtime = method, data, omega, runtime
        self.options, self.damage, self.fidelity = options, damage, fidelity
        self.common = {"dtype": dtype, "progress": progress, "seed": seed}
        self.solution = None

    def states(self, every=None):
        soft_mask = self.method.soft_mask
        extra = {"fidelity": self.fidelity} if soft_mask and self.fidelity is not None else {}
        solved = self.method.call(
            self.data, self.omega, self.runtime, self.options, **self.common, **extra
        )
        solved = np.asarray(solved, np.float64)
        if self.damage is not None and not soft_mask:
            solved = np.where(
                self.omega, self.damage * solved + (1 - self.damage) * self.data, self.data
            )
        self.solution = solved
        return iter(())
