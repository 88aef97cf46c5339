"""Long runs: when clpde draws a progress bar (the one policy of the library and the command
line), and the states a run yields.

``progress=True`` always draws one, ``False`` never, and ``None`` (the default) decides:
only on a terminal (bars go to stderr), and only once the run has lasted `DELAY_S` seconds,
so that short runs print nothing and long ones show their progress on any device. The
delay is measured, not predicted from a cell-update count: the same count takes seconds on
a GPU and minutes on a CPU.

Device work is enqueued asynchronously, so a bar over enqueued steps would race to its end
and then wait in silence. Given the device `queue`, `progress_range` waits for the queue
every few steps, as many as take about `SYNC_S` seconds, so the bar moves with the work
actually done.

``progress`` may also be a callable, ``progress(done, total)``: it is called instead of
drawing a bar each time the run advances (``total`` is None when the length is unknown), and
it may stop the run by raising any exception, which propagates to the caller. This is how a
graphical front end (clpde's napari plugin) shows progress and cancels a run.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from tqdm.auto import tqdm

from .errors import InputError

# What every `progress=` argument of clpde accepts.
Progress = bool | None | Callable[[float, float | None], Any]

# Seconds a run with progress=None lasts before its bar appears.
DELAY_S = 2.0
# Seconds of device work between the waits that move a bar (see progress_range).
SYNC_S = 0.25


def on_terminal() -> bool:
    """Whether stderr, where the bars go, is a terminal (the command line's `progress`)."""
    return sys.stderr.isatty()


def bar_disabled(progress: bool | None, long_run: bool = True) -> bool | None:
    """tqdm's ``disable=`` for a `progress` argument; None lets tqdm hide the bar when
    stderr is not a terminal."""
    if progress is None:
        return None if long_run else True
    return not progress


def _delay(progress: bool | None) -> float:
    return DELAY_S if progress is None else 0.0


class CallbackBar:
    """The part of tqdm's interface that clpde's runs use, reporting to a callable.

    Runs call ``update``; the callable hears ``(done, total)`` after each, and an exception it
    raises (a cancel) leaves the run at once. ``disable`` is False so that runs which only
    synchronise the device for a visible bar do so for the callable too.
    """

    disable = False

    def __init__(
        self,
        callback: Callable,
        total: float | None = None,
        iterable: Iterable | None = None,
        initial: float = 0,
        **_options,
    ):
        self.callback, self.total, self.iterable, self.n = callback, total, iterable, initial

    def update(self, n: float = 1) -> None:
        self.n += n
        self.callback(self.n, self.total)

    def __iter__(self) -> Iterator:
        for item in self.iterable:
            yield item
            self.update(1)

    def __enter__(self) -> CallbackBar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        pass

    def set_postfix_str(self, *_args, **_kwargs) -> None:
        pass

    def write(self, text: str) -> None:
        print(text, file=sys.stderr)


def check_progress(progress: Progress) -> None:
    """One clear line for a `progress` argument that is neither a flag nor a callable."""
    if progress is not None and not isinstance(progress, bool) and not callable(progress):
        raise InputError(
            f"progress must be True, False, None or a callable "
            f"progress(done, total), not {progress!r}"
        )


def progress_bar(
    progress: Progress, total: float | None, desc: str, *, long_run: bool = True, **options
) -> tqdm | CallbackBar:
    """A tqdm bar over `total` units, drawn by the policy of `bar_disabled` and, with
    progress=None, only after `DELAY_S` seconds; a `CallbackBar` when `progress` is a
    callable."""
    check_progress(progress)
    if callable(progress):
        return CallbackBar(progress, total, **options)
    options.setdefault("delay", _delay(progress))
    return tqdm(total=total, desc=desc, disable=bar_disabled(progress, long_run), **options)


def progress_range(
    progress: Progress, steps: int, desc: str, *, long_run: bool = True, queue=None, **options
) -> Iterator[int]:
    """range(steps) under a bar drawn by the policy of `progress_bar`.

    With the device's `queue`, the loop waits for the queue after a batch of steps whose
    size adapts so that a batch takes about `SYNC_S` seconds (only while a bar may be
    drawn): the bar then counts steps done, not steps enqueued.
    """
    bar = progress_bar(progress, steps, desc, long_run=long_run, **options)
    with bar:
        if bar.disable or queue is None:
            for n in range(steps):
                yield n
                bar.update(1)
            return
        batch, pending, start = 1, 0, time.perf_counter()
        for n in range(steps):
            yield n
            pending += 1
            if pending >= batch or n == steps - 1:
                queue.finish()
                now = time.perf_counter()
                per_step = (now - start) / pending
                batch = max(1, min(1000, int(SYNC_S / max(per_step, 1e-6))))
                bar.update(pending)
                pending, start = 0, now


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
