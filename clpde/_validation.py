"""The checks of user parameters that several modules share, with the error they raise.

Each check returns the value in the form the code uses (a float, an int) or raises
`InputError` with a one-line message that names the parameter and the fix.
"""

from __future__ import annotations

import numpy as np

from .runtime import ClpdeError


class InputError(ClpdeError, ValueError):
    """An input array or parameter that clpde cannot use; the message says how to fix it."""


def positive(name: str, value) -> float:
    """A parameter that must be a finite positive number, as a float."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a positive number, not {value!r}") from None
    if not np.isfinite(number) or number <= 0:
        raise InputError(f"{name} must be a positive number, not {value!r}")
    return number


def check_steps(steps) -> int:
    """A number of steps: a non-negative integer (bools are refused)."""
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, not {steps!r}")
    return int(steps)


def check_time_step(dt, limit: float, what: str) -> float:
    """An explicit scheme's time step: 0.8 of the stability `limit` when None, else a
    positive number no larger than the limit. `what` names the scheme in the message."""
    if dt is None:
        return 0.8 * limit
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"dt must be a positive number, not {dt}")
    if dt > limit * (1 + 1e-9):
        raise InputError(
            f"dt={dt:g} is beyond the stability limit {limit:g} of the explicit {what} scheme; "
            f"use dt <= {limit:g}, or leave dt out for the default {0.8 * limit:g}"
        )
    return dt
