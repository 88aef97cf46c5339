"""Explicit flows on implicit surfaces, stepped over the narrow band on the device.

Every step is two kernels: the flow's update over the step band (cur -> tmp), then the
closest-point re-extension of the whole extension band (tmp -> cur). State stays on the
device from upload to the final read-back; no host round-trip per step.
"""

from __future__ import annotations

import math

import numpy as np
from tqdm.auto import tqdm

from ..imagedata import InputError

# One-sided difference choices per axis: bit set = backward gradient (forward divergence).
_ALL_SIDES = tuple(range(8))


def stability_limit(surf, flow: str = "heat") -> float:
    """Largest stable explicit time step (world time units) of a flow on `surf`."""
    h2 = surf.spacing**2
    if flow == "heat":
        # |N| P_N has norm <= |N| and the one-sided div is minus the transpose of the
        # one-sided grad: the operator's spectrum lies in [-12/h^2, 0] for a distance
        # function, as for the 7-point Laplacian.
        return h2 / 6.0
    raise InputError(f"unknown surface flow {flow!r}")


def _check_time(t, dt, limit: float, what: str) -> tuple[int, float]:
    """(steps, dt) covering time t; an explicit unstable dt is an error naming the limit."""
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise InputError(f"t must be a non-negative number, not {t!r}") from None
    if not math.isfinite(t) or t < 0:
        raise InputError(f"t must be a non-negative number, not {t!r}")
    if dt is None:
        steps = max(1, math.ceil(t / limit - 1e-9))
        return steps, t / steps
    dt = float(dt)
    if not math.isfinite(dt) or dt <= 0:
        raise InputError(f"dt must be a positive number, not {dt!r}")
    if dt > limit * (1 + 1e-9):
        raise InputError(
            f"dt={dt:g} is above the {what} stability limit {limit:g} for spacing; use dt <= {limit:g} "
            "(or leave dt=None to pick it)"
        )
    steps = max(1, math.ceil(t / dt - 1e-9))
    return steps, t / steps


def _offsets(grid, sides: int):
    """Signed one-sided difference offsets (ex, ey, ez) for a choice of sides (bits x, y, z)."""
    sx, sxy = int(grid.sx), int(grid.sxy)
    return tuple(np.int32(-s if (sides >> a) & 1 else s) for a, s in enumerate((1, sx, sxy)))


class BandFlow:
    """Device state of data on a surface: `cur` (extended) and a scratch volume `tmp`."""

    def __init__(self, surf, u, normalize: bool = False):
        self.surf = surf
        self.input = np.asarray(u)
        data = surf._as_channels(u)
        self.nc = data.shape[0]
        self.normalize = normalize
        g = surf.grid
        self.cur = g.upload(data)
        self.tmp = self.cur.copy()
        self._extend_kernel = g.kernel("extend_cp", INTERP=surf.interp, NC=self.nc,
                                       NORMALIZE=int(normalize))
        self.extend()

    def extend(self) -> None:
        """Re-extend cur along the normals (through tmp; cur holds the result)."""
        self._extend(self.cur, self.tmp)
        self.cur, self.tmp = self.tmp, self.cur

    def _extend(self, src, dst) -> None:
        s, g = self.surf, self.surf.grid
        g.launch_list(
            self._extend_kernel, s.ext_band, src.data, dst.data, s.cp[0].data, s.cp[1].data,
            s.cp[2].data, *g.strides(), *g.padded_dims(),
        )

    def after_step(self) -> None:
        """The step wrote tmp over the step band: extend it back into cur."""
        self._extend(self.tmp, self.cur)

    def result(self) -> np.ndarray:
        out = self.surf.grid.download(self.cur)
        out = out[0] if self.input.shape == self.surf.shape else out
        dtype = self.input.dtype if np.issubdtype(self.input.dtype, np.floating) else np.float64
        return out.astype(dtype)


def _progress(progress, steps: int, desc: str):
    disable = None if progress is None else not progress
    return tqdm(range(steps), desc=desc, disable=disable, leave=False)


def heat(surf, u, t, dt=None, *, weighted=False, alternate=False, progress=None) -> np.ndarray:
    """Intrinsic heat flow on `surf` for time t: eq. (4.8), or (4.7) with weighted=True.

    Appendix E's scheme (forward gradient, projection on the tangent plane with N from
    central differences of psi, backward divergence), explicit Euler steps, whole-band
    closest-point re-extension after each step. alternate=True cycles through the eight
    forward/backward combinations step by step.
    """
    steps, dt = _check_time(t, dt, stability_limit(surf, "heat"), "heat flow")
    flow = BandFlow(surf, u)
    g = surf.grid
    kernel = g.kernel("heat_step", WEIGHTED=int(bool(weighted)))
    r = g.scalar(dt / surf.spacing**2)
    for n in _progress(progress, steps, "surface heat"):
        sides = _ALL_SIDES[n % 8] if alternate else 0
        g.launch_list(
            kernel, surf.step_band, flow.cur.data, flow.tmp.data, surf.psi_dev.data, r,
            *_offsets(g, sides), *g.strides(), channels=flow.nc,
        )
        flow.after_step()
    return flow.result()
