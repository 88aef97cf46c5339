"""Planar diffusion flows: heat, Perona-Malik, total variation, curvature, and ROF denoising.

`PlanarFlow` keeps the state on the device and enqueues steps back to back; `diffuse` and
`denoise_tv` are the one-call forms on numpy arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from .fields import Field, Grid, PingPong
from .imagedata import InputError, to_kernel_layout
from .imagedata import positive as _positive
from .runtime import get_runtime

FLOWS = ("heat", "perona-malik", "tv", "curvature")
# TV's regularisation of |grad u| on [0, 1] data: about one grey level of 8-bit data, so
# that only gradients below it (noise, quantisation) are smoothed like heat while every
# visible edge moves as TV: regions flatten and edges stay. At 0.05 (12 grey levels) most of
# a photo's gradients were below eps and TV flow blurred it more than heat did.
TV_EPS = 0.005
# The parameters each flow takes besides dt; any other is refused rather than ignored.
FLOW_PARAMS = {"heat": (), "perona-malik": ("kappa", "edge"), "tv": ("eps",),
               "curvature": ("eps", "weight")}


def _check_dt(dt, limit: float, what: str) -> float:
    if dt is None:
        return 0.8 * limit
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"dt must be a positive number, not {dt}")
    if dt > limit * (1 + 1e-9):
        raise InputError(
            f"dt={dt:g} is beyond the stability limit {limit:g} of the explicit {what} scheme; "
            f"use dt <= {limit:g} (or leave dt=None for {0.8 * limit:g})"
        )
    return dt


def stability_limit(flow: str, eps: float = 0.0, lam: float = 0.0) -> float:
    """Largest stable explicit time step of a planar flow (unit grid spacing)."""
    if flow in ("heat", "perona-malik", "curvature"):
        return 0.25
    if flow in ("tv", "rof"):
        return 1.0 / (4.0 / eps + lam)
    raise InputError(f"unknown flow {flow!r}; choose one of {', '.join(FLOWS)}")



@dataclass
class FlowState:
    """One yielded state of a running flow."""

    step: int
    time: float
    image: np.ndarray
    info: dict = field(default_factory=dict)


class PlanarFlow:
    """A planar flow whose state stays on the device between calls.

    >>> flow = PlanarFlow(image, "tv")
    >>> for state in flow.iterate(steps=400, every=100):
    ...     show(state.image)
    """

    def __init__(self, image, flow: str = "heat", *, dt=None, channel_axis=None, device=None,
                 precision=None, kappa=None, edge=None, eps=None, weight=None):
        if flow not in FLOWS:
            raise InputError(f"unknown flow {flow!r}; choose one of {', '.join(FLOWS)}")
        given = {"kappa": kappa, "edge": edge, "eps": eps, "weight": weight}
        for name, value in given.items():
            if value is not None and name not in FLOW_PARAMS[flow]:
                users = [f for f, params in FLOW_PARAMS.items() if name in params]
                raise InputError(f"{name} applies to the {' and '.join(users)} flow"
                                 f"{'s' if len(users) > 1 else ''}, not {flow}; leave it out")
        kappa = 0.05 if kappa is None else kappa
        edge = "exp" if edge is None else edge
        data, self.layout = to_kernel_layout(image, channel_axis)
        self.runtime = get_runtime(device)
        dtype = np.dtype(precision or np.float32)
        nc, ny, nx = data.shape
        self.grid = Grid(self.runtime, nx, ny, nc, 1, dtype)
        self.flow = flow
        self.steps_done = 0
        self.time = 0.0
        self.pair = PingPong(Field.from_host(self.grid, data))
        self._setup(flow, dt, kappa, edge, eps, weight)

    def _setup(self, flow, dt, kappa, edge, eps, weight):
        g = self.grid
        if flow == "heat":
            self.dt = _check_dt(dt, stability_limit(flow), "heat")
            kernel = g.kernel("planar.cl", "heat_step")
            self._extra = ()
        elif flow == "perona-malik":
            if edge not in ("exp", "rational"):
                raise InputError(f"edge must be 'exp' or 'rational', not {edge!r}")
            kappa = _positive("kappa", kappa)
            self.dt = _check_dt(dt, stability_limit(flow), "Perona-Malik")
            kernel = g.kernel("planar.cl", "perona_malik_step", EDGE_STOP=int(edge == "rational"))
            self._extra = (g.scalar(1.0 / kappa**2),)
        elif flow == "tv":
            eps = _positive("eps", TV_EPS if eps is None else eps)
            self.dt = _check_dt(dt, stability_limit(flow, eps), f"TV (eps={eps:g})")
            kernel = g.kernel("planar.cl", "tv_step")
            self._extra = (g.scalar(eps * eps),)
        else:  # curvature
            eps = 1e-10 if eps is None else float(eps)
            self.dt = _check_dt(dt, stability_limit(flow), "curvature")
            if weight is None:
                kernel = g.kernel("planar.cl", "curvature_step")
                weight_buf = self.pair.cur.data.data  # unread when HAS_WEIGHT is 0
            else:
                weight = np.asarray(weight, np.float64)
                if weight.shape != (g.ny, g.nx) or not np.isfinite(weight).all():
                    raise InputError(
                        f"weight must be a finite ({g.ny}, {g.nx}) array, got shape {weight.shape}"
                    )
                wgrid = Grid(self.runtime, g.nx, g.ny, 1, 1, g.dtype)
                self._weight = Field.from_host(wgrid, weight[np.newaxis])
                weight_buf = self._weight.data.data
                kernel = g.kernel("planar.cl", "curvature_step", HAS_WEIGHT=1)
            self._extra = (weight_buf, g.scalar(0), g.scalar(eps))
        self._kernel = kernel

    def _enqueue_step(self):
        g = self.grid
        if self.flow == "curvature":  # the weight buffer comes before dt
            args = (self._extra[0], g.scalar(self.dt), self._extra[2])
        else:
            args = (g.scalar(self.dt), *self._extra)
        g.launch(self._kernel, self.pair.cur.data.data, self.pair.nxt.data.data, *args)
        self.pair.swap()
        self.steps_done += 1
        self.time += self.dt

    def run(self, steps: int, progress=None) -> PlanarFlow:
        """Enqueue `steps` steps; the host only waits to move the progress bar."""
        steps = _check_steps(steps)
        bar = tqdm(total=steps, desc=f"clpde {self.flow}", unit="step",
                   disable=_progress_disabled(progress, steps, self.grid))
        chunk = 50
        with bar:
            for start in range(0, steps, chunk):
                for _ in range(min(chunk, steps - start)):
                    self._enqueue_step()
                if not bar.disable:
                    self.runtime.queue.finish()
                    bar.update(min(chunk, steps - start))
        return self

    def iterate(self, steps: int, every: int):
        """Run `steps` steps, yielding a FlowState every `every` steps (and at the end)."""
        steps = _check_steps(steps)
        every = max(1, int(every))
        done = 0
        while done < steps:
            n = min(every, steps - done)
            self.run(n, progress=False)
            done += n
            yield FlowState(self.steps_done, self.time, self.result())

    def result(self) -> np.ndarray:
        """The current state as an array like the input (one device-to-host copy)."""
        return self.layout.restore(self.pair.cur.to_host())


def _check_steps(steps) -> int:
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, not {steps!r}")
    return int(steps)


def _progress_disabled(progress, steps: int, grid: Grid):
    if progress is None:  # automatic: only for long runs, and only on a terminal
        return None if steps * grid.nx * grid.ny * grid.nc > 2e9 else True
    return not progress


def diffuse(image, flow: str = "heat", steps: int = 100, dt=None, channel_axis=None,
            device=None, *, progress=None, precision=None, **params) -> np.ndarray:
    """Run a planar diffusion flow for `steps` explicit steps.

    flow: 'heat' (u_t = Lap u), 'perona-malik' (params kappa, edge='exp'|'rational'),
    'tv' (u_t = div(grad u / |grad u|_eps), param eps, default TV_EPS = 0.005) or 'curvature'
    (u_t = g kappa |grad u|, params weight=g, eps). Data is scaled to [0, 1] internally,
    so kappa and eps are in those units. The time step defaults to 0.8 of the stability
    limit; a larger dt than the limit is an error. Output has the input's dtype and shape.
    """
    unknown = sorted(set(params) - {p for names in FLOW_PARAMS.values() for p in names})
    if unknown:
        listed = "; ".join(f"{f}: {', '.join(p) or 'none'}" for f, p in FLOW_PARAMS.items())
        raise InputError(f"diffuse takes no parameter {unknown[0]!r}; the flows take ({listed})")
    state = PlanarFlow(image, flow, dt=dt, channel_axis=channel_axis, device=device,
                       precision=precision, **params)
    return state.run(steps, progress).result()


# denoise_tv moved to clpde/rof.py; kept importable from here.
from .rof import DenoiseInfo, denoise_tv  # noqa: F401
