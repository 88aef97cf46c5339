"""Long runs: when clpde draws a progress bar (the one policy of the library and the command
line), and the states a run yields.

``progress=True`` always draws one, ``False`` never, and ``None`` (the default) decides:
only on a terminal (bars go to stderr), and, where the caller says how long the run is,
only for a long one.
"""

from __future__ import annotations

import sys

from tqdm.auto import tqdm

# The automatic bar of a grid flow waits for runs of more cell updates than this (seconds of
# work on a GPU): shorter ones would only flash a bar, and reading it costs a queue wait.
LONG_RUN_CELL_UPDATES = 2e9


def is_long_run(steps: int, cells: int) -> bool:
    """Whether `steps` steps over `cells` cells make a run long enough for an automatic bar."""
    return steps * cells > LONG_RUN_CELL_UPDATES


def on_terminal() -> bool:
    """Whether stderr, where the bars go, is a terminal (the command line's `progress`)."""
    return sys.stderr.isatty()


def bar_disabled(progress: bool | None, long_run: bool = True) -> bool | None:
    """tqdm's ``disable=`` for a `progress` argument; None lets tqdm hide the bar when
    stderr is not a terminal."""
    if progress is None:
        return None if long_run else True
    return not progress


def progress_bar(progress: bool | None, total: int, desc: str, *, long_run: bool = True,
                 **options) -> tqdm:
    """A tqdm bar over `total` units, drawn by the policy of `bar_disabled`."""
    return tqdm(total=total, desc=desc, disable=bar_disabled(progress, long_run), **options)


def progress_range(progress: bool | None, steps: int, desc: str, *, long_run: bool = True,
                   **options) -> tqdm:
    """range(steps) under a tqdm bar drawn by the policy of `bar_disabled`."""
    return tqdm(range(steps), desc=desc, disable=bar_disabled(progress, long_run), **options)


# Every object that runs for long (PlanarFlow, Inpainting, MorphingTracker, RegionTracker)
# has one iteration verb, `iterate`, yielding `State`s: each has `step` (how far the run has
# got, in its own unit) and `time` (its time, or None where the run has none).
class State:
    """Base of the states a long run yields.

    Subclasses are dataclasses and each has `step` (int: flow steps, steps on an
    inpainting level, a frame's index) and `time` (float, or None for runs without one).
    """

    __slots__ = ()
    step: int
    time: float | None
