"""The shapes every long run shares: the state it yields and its deprecated old names.

Every object that runs for long (PlanarFlow, Inpainting, MorphingTracker, RegionTracker)
has one iteration verb, `iterate`, yielding `State`s: each has `step` (how far the run has
got, in its own unit) and `time` (its time, or None where the run has none). The old verbs,
keywords and spellings stay for one release as aliases that raise a DeprecationWarning.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import Any

from .errors import InputError
from .runtime import Runtime

__all__ = ["DeviceLike", "State", "deprecated", "renamed_keyword"]

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


def _warn(message: str, up: int) -> None:
    """A DeprecationWarning pointing `up` frames above the caller (at the user's line)."""
    warnings.warn(message, DeprecationWarning, stacklevel=up + 2)


def deprecated(new: str, old: str) -> Callable[[Callable], Callable]:
    """Decorator making a method `old` a deprecated alias of `new` (same arguments)."""

    def wrap(func):
        @functools.wraps(func)
        def alias(self, *args, **kwargs):
            _warn(f"{type(self).__name__}.{old} is deprecated; use {new} (same arguments)", 1)
            return getattr(self, new)(*args, **kwargs)

        return alias

    return wrap


def renamed_keyword(new: str, new_value: Any, old: str, old_value: Any, default: Any = None) -> Any:
    """The value of keyword `new`, taking a deprecated `old` spelling of it when given.

    Both None (or `default`) means the default; both given is an error."""
    if old_value is None:
        return new_value
    _warn(f"{old}= is deprecated; use {new}=", 2)
    if new_value is not None and new_value is not default:

        raise InputError(f"pass {new}= only ({old}= is its deprecated old name)")
    return old_value
