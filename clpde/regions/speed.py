"""The speed that moves the surface in region tracking, from `track_region`'s `beta`: a
constant, a named curvature speed, an array on the grid, or a function of time."""

from __future__ import annotations

import inspect

import numpy as np

from ..errors import InputError


def _time_dependent(beta) -> bool:
    """True for a callable taking (x, y, z, t), False for one taking (x, y, z)."""
    try:
        params = inspect.signature(beta).parameters.values()
    except (TypeError, ValueError):  # builtins without a signature: f(x, y, z)
        return False
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 4


def _beta_array(values, shape, when="") -> np.ndarray:
    """A user's beta (number or array) as an array of phi's shape, checked."""
    arr = np.asarray(values, np.float64)
    try:
        arr = np.broadcast_to(arr, shape)
    except ValueError:
        raise InputError(
            f"a beta array{when} must have phi's shape {shape}, got {arr.shape}"
        ) from None
    if not np.all(np.isfinite(arr)):
        raise InputError(f"beta{when} contains NaN or infinite values")
    return arr


def _speed_setup(beta, target, weight, h, shape, coords):
    """(speed name, scale, aux array, aux as a function of time or None) for RegionTracker
    from the user's beta."""
    if isinstance(beta, str):
        if beta == "mean-curvature":
            return "mean-curvature", weight / h**2, None, None
        if beta == "gaussian":
            return "gaussian", weight / h**3, None, None
        if beta == "morph":
            if target is None:
                raise InputError(
                    "beta='morph' needs target=: the target shape's signed distance volume"
                )
            target = np.asarray(target, np.float64)
            if target.shape != shape:
                raise InputError(f"target must have phi's shape {shape}, got {target.shape}")
            return "morph", weight, target, None
        raise InputError(
            f"beta must be a number, an array, a callable or one of "
            f"'mean-curvature', 'gaussian', 'morph'; not {beta!r}"
        )
    if callable(beta):
        if _time_dependent(beta):

            def beta_at(t):
                return _beta_array(beta(*coords, t), shape, f" (the callable at t = {t:g})")

            return "array", -weight / h, beta_at(0.0), beta_at
        beta = _beta_array(beta(*coords), shape, " (the callable's result)")
    arr = np.asarray(beta, np.float64)
    if arr.ndim == 0:
        if not np.isfinite(arr):
            raise InputError(f"beta must be finite, not {beta!r}")
        return "constant", -weight * float(arr) / h, None, None
    if arr.shape != shape:
        raise InputError(f"a beta array must have phi's shape {shape}, got {arr.shape}")
    return "array", -weight / h, _beta_array(arr, shape), None


def surface_motion(beta, velocity, target, weight: float, h: float, shape, origin) -> tuple:
    """(speed name, scale, aux, aux_at, velocity in cells per unit time or None) for
    RegionTracker: a rigid translation when `velocity` is given, else the speed of beta
    (the callables sampled at the world coordinates of phi's grid, `origin` and `h`)."""
    if velocity is not None:
        vel = np.asarray(velocity, np.float64).reshape(-1)
        if vel.shape != (3,) or not np.all(np.isfinite(vel)):
            raise InputError(
                f"velocity must be three finite numbers (vx, vy, vz), got {velocity!r}"
            )
        return "constant", 0.0, None, None, vel / h
    nz, ny, nx = shape
    coords = (
        origin[0] + h * np.arange(nx)[None, None, :],
        origin[1] + h * np.arange(ny)[None, :, None],
        origin[2] + h * np.arange(nz)[:, None, None],
    )
    return (*_speed_setup(beta, target, float(weight), h, shape, coords), None)
