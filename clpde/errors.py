"""clpde's errors, each with one home: every message names the problem and the way out.

A user catches `ClpdeError` for all of them, or `InputError` (also a ValueError) for bad
arguments and files; the command line prints the message and exits with status 2 for those.
"""

from __future__ import annotations


class ClpdeError(RuntimeError):
    """Base class of clpde's own errors (device, build and input problems)."""


class NoDeviceError(ClpdeError):
    """No OpenCL device that clpde can use; the message says what to install or choose."""


class KernelBuildError(ClpdeError):
    """An OpenCL program that did not build on the chosen device (the log is in the message)."""


class DeviceMemoryError(ClpdeError, MemoryError):
    """A request that cannot fit the device's memory; the message gives the size and the way out."""


class DeviceLimitError(ClpdeError):
    """A kernel that cannot fit the device's limits (local memory, work-group size); the
    message names the limit and the way out."""


class InputError(ClpdeError, ValueError):
    """An input array or parameter that clpde cannot use; the message says how to fix it."""


def error_message(exc: BaseException) -> str:
    """An error as the one line the command line and a batch's report show."""
    if isinstance(exc, OSError) and exc.strerror:
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror}{where}"
    return str(exc) or type(exc).__name__
