"""The shapes every long run shares: the state it yields, and what `device=` takes.

Every object that runs for long (PlanarFlow, Inpainting, MorphingTracker, RegionTracker)
has one iteration verb, `iterate`, yielding `State`s: each has `step` (how far the run has
got, in its own unit) and `time` (its time, or None where the run has none).
"""

from __future__ import annotations

from .runtime import Runtime

__all__ = ["DeviceLike", "State"]

# What every `device=` takes: a name part ('cpu', 'gpu', ...), an index, a Runtime, or None
# for the default choice (see clpde.devices).
DeviceLike = str | int | Runtime | None


class State:
    """Base of the states a long run yields.

    Subclasses are dataclasses and each has `step` (int: flow steps, steps on an
    inpainting level, a frame's index) and `time` (float, or None for runs without one).
    """

    __slots__ = ()
    step: int
    time: float | None
