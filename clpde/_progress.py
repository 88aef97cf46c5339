"""When clpde draws a progress bar: the one policy of the library and the command line.

``progress=True`` always draws one, ``False`` never, and ``None`` (the default) decides:
only on a terminal (bars go to stderr), and, where the caller says how long the run is,
only for a long one.

``progress`` may also be a callable, ``progress(done, total)``: it is called instead of
drawing a bar each time the run advances (``total`` is None when the length is unknown), and
it may stop the run by raising any exception, which propagates to the caller. This is how a
graphical front end (clpde's napari plugin) shows progress and cancels a run.
"""

from __future__ import annotations

import sys

from collections.abc import Callable, Iterable, Iterator
from typing import Any, Union

from tqdm.auto import tqdm

# What every `progress=` argument of clpde accepts.
Progress = Union[bool, None, Callable[[float, Union[float, None]], Any]]

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


class CallbackBar:
    """The part of tqdm's interface that clpde's runs use, reporting to a callable.

    Runs call ``update``; the callable hears ``(done, total)`` after each, and an exception it
    raises (a cancel) leaves the run at once. ``disable`` is False so that runs which only
    synchronise the device for a visible bar do so for the callable too.
    """

    disable = False

    def __init__(self, callback: Callable, total: float | None = None,
                 iterable: Iterable | None = None, initial: float = 0, **_options):
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
        from .imagedata import InputError

        raise InputError(f"progress must be True, False, None or a callable "
                         f"progress(done, total), not {progress!r}")


def progress_bar(progress: Progress, total: float | None, desc: str, *, long_run: bool = True,
                 **options) -> tqdm | CallbackBar:
    """A tqdm bar over `total` units, drawn by the policy of `bar_disabled`, or a
    `CallbackBar` when `progress` is a callable."""
    check_progress(progress)
    if callable(progress):
        return CallbackBar(progress, total, **options)
    return tqdm(total=total, desc=desc, disable=bar_disabled(progress, long_run), **options)


def progress_range(progress: Progress, steps: int, desc: str, *, long_run: bool = True,
                   **options) -> tqdm | CallbackBar:
    """range(steps) under a tqdm bar drawn by the policy of `bar_disabled` (or reported to a
    callable `progress`)."""
    check_progress(progress)
    if callable(progress):
        return CallbackBar(progress, steps, iterable=range(steps))
    return tqdm(range(steps), desc=desc, disable=bar_disabled(progress, long_run), **options)
