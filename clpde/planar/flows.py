"""Planar diffusion flows: heat, Perona-Malik, total variation, curvature, and ROF denoising.

`PlanarFlow` keeps the state on the device and enqueues steps back to back; `diffuse` and
`denoise_tv` are the one-call forms on numpy arrays.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from .._progress import State, progress_bar
from ..errors import InputError
from ..fields import Field, Grid, PingPong, check_fits
from ..imagedata import check_steps, check_time_step, positive, to_kernel_layout
from ..runtime import get_runtime
from ..volumes.flows import diffuse_volume
from ..volumes.grid import is_volume
from . import bounded

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("planar/planar.cl", "planar/catte.cl")

FLOWS = ("heat", "perona-malik", "tv", "curvature")
# TV's regularisation of |grad u| on [0, 1] data: about one grey level of 8-bit data, so
# that only gradients below it (noise, quantisation) are smoothed like heat while every
# visible edge moves as TV: regions flatten and edges stay. At 0.05 (12 grey levels) most of
# a photo's gradients were below eps and TV flow blurred it more than heat did.
TV_EPS = 0.005
# The parameters each flow takes besides dt; any other is refused rather than ignored.
FLOW_PARAMS = {
    "heat": (),
    "perona-malik": ("kappa", "edge", "presmooth"),
    "tv": ("eps",),
    "curvature": ("eps", "weight"),
}


def gaussian_weights(presmooth: float) -> np.ndarray:
    """The one-sided weights w[0..r] of a sampled Gaussian of standard deviation `presmooth`
    pixels, r = ceil(3 presmooth), normalised so that w[0] + 2 (w[1] + ... + w[r]) = 1
    (kernels/planar/catte.cl's catte_gauss_rows and catte_gauss_cols). presmooth = 0 gives [1]: no
    smoothing.

    Parameters
    ----------
    presmooth : float
        The standard deviation in pixels, 0 or more.

    Returns
    -------
    ndarray
        The r + 1 weights (float64).

    Raises
    ------
    InputError
        For a negative or non-finite presmooth.

    Examples
    --------
    >>> from clpde.planar.flows import gaussian_weights
    >>> w = gaussian_weights(1.0)
    >>> len(w), round(float(w[0] + 2 * w[1:].sum()), 12)
    (4, 1.0)
    """
    if not np.isfinite(presmooth) or presmooth < 0:
        raise InputError(f"presmooth must be a number >= 0 (pixels), not {presmooth!r}")
    if presmooth == 0:
        return np.ones(1)
    radius = int(np.ceil(3 * presmooth))
    w = np.exp(-0.5 * (np.arange(radius + 1) / presmooth) ** 2)
    return w / (w[0] + 2 * w[1:].sum())


def stability_limit(flow: str, eps: float = 0.0, lam: float = 0.0) -> float:
    """Largest stable explicit time step of a planar flow (unit grid spacing).

    Parameters
    ----------
    flow : {'heat', 'perona-malik', 'tv', 'curvature', 'rof'}
        The flow; 'rof' is denoise_tv's gradient method (TV flow with fidelity).
    eps : float
        TV's regularisation of |grad u| (needed by 'tv' and 'rof').
    lam : float
        The fidelity weight lambda of 'rof'.

    Returns
    -------
    float
        1/4 for heat, Perona-Malik and curvature flow; 1 / (4/eps + lam) for TV and ROF,
        whose face coefficients reach 1/eps. `diffuse` runs at 0.8 of it by default.

    Examples
    --------
    >>> from clpde import stability_limit
    >>> stability_limit("heat")
    0.25
    >>> stability_limit("tv", eps=0.01)
    0.0025
    """
    if flow in ("heat", "perona-malik", "curvature"):
        return 0.25
    if flow in ("tv", "rof"):
        eps = positive("eps", eps)
        if not np.isfinite(lam) or lam < 0:
            raise InputError(f"lam must be a number >= 0, not {lam!r}")
        return 1.0 / (4.0 / eps + lam)
    raise InputError(f"unknown flow {flow!r}; choose one of {', '.join(FLOWS)}")


def _check_flow_params(flow: str, given: dict) -> None:
    """Refuse a parameter the flow does not take, rather than ignore it."""
    for name, value in given.items():
        if value is not None and name not in FLOW_PARAMS[flow]:
            users = [f for f, params in FLOW_PARAMS.items() if name in params]
            raise InputError(
                f"{name} applies to the {' and '.join(users)} flow"
                f"{'s' if len(users) > 1 else ''}, not {flow}; leave it out"
            )


@dataclass
class DiffuseInfo:
    """What a `diffuse` run did: the steps run, the time step, the flow's time reached
    (steps * dt), the flow and the largest stable time step (`stability_limit`)."""

    steps: int
    dt: float
    time: float
    flow: str
    stability_limit: float


@dataclass
class FlowState(State):
    """One yielded state of a running flow: steps and time so far, the image like the input."""

    step: int
    time: float
    image: np.ndarray
    info: dict = field(default_factory=dict)


class PlanarFlow:
    """A planar flow whose state stays on the device between calls.

    `run` enqueues steps, `iterate` yields a `FlowState` every few steps, `result` copies
    the current state back as an array like the input.

    Parameters
    ----------
    image : array_like
        Greyscale (rows, cols) or colour image (with `channel_axis`), any int or float dtype.
    flow : {'heat', 'perona-malik', 'tv', 'curvature'}
        The flow, as for `diffuse`.
    dt : float, optional
        Time step; 0.8 of the flow's stability limit by default.
    channel_axis : int, optional
        The axis of the colour channels; None for a greyscale image.
    device : str or int, optional
        The OpenCL device, as for `clpde.use_device`; the default device if None.
    dtype : {float32, float64}, optional
        The device's arithmetic (float32 by default).
    kappa : float, optional
        Perona-Malik's edge threshold, intensities in [0, 1] (0.05 by default).
    edge : {'exp', 'rational'}, optional
        Perona-Malik's edge-stopping function ('exp' by default).
    eps : float, optional
        Regularisation of |grad u| for 'tv' and 'curvature', intensities in [0, 1].
    weight : array_like, optional
        The curvature flow's speed g, an array of the image's (rows, cols).
    presmooth : float, optional
        Perona-Malik: read the edge-stopping function from the image smoothed by a
        Gaussian of this many pixels (the regularised flow of Catte et al.; isolated noise
        spikes then diffuse too). None: the plain flow.

    Raises
    ------
    InputError
        For an unknown flow, a parameter the flow does not take, or an unusable image.

    Attributes
    ----------
    steps_done : int
        Steps run so far.
    time : float
        The flow's time, steps_done * dt.
    dt : float
        The time step (0.8 of `stability_limit` unless given).

    Examples
    --------
    >>> import numpy as np
    >>> from clpde import PlanarFlow
    >>> image = np.zeros((32, 32), np.uint8)
    >>> image[8:24, 8:24] = 200
    >>> flow = PlanarFlow(image, "tv")
    >>> [state.step for state in flow.iterate(steps=300, every=100)]
    [100, 200, 300]
    >>> flow.result().dtype, flow.steps_done
    (dtype('uint8'), 300)
    """

    def __init__(
        self,
        image: ArrayLike,
        flow: str = "heat",
        *,
        dt: float | None = None,
        channel_axis: int | None = None,
        device: str | int | None = None,
        dtype: DTypeLike | None = None,
        kappa: float | None = None,
        edge: str | None = None,
        eps: float | None = None,
        weight: ArrayLike | None = None,
        presmooth: float | None = None,
    ):
        if flow not in FLOWS:
            raise InputError(f"unknown flow {flow!r}; choose one of {', '.join(FLOWS)}")
        _check_flow_params(
            flow,
            {"kappa": kappa, "edge": edge, "eps": eps, "weight": weight, "presmooth": presmooth},
        )
        kappa = 0.05 if kappa is None else kappa
        edge = "exp" if edge is None else edge
        self.runtime = get_runtime(device)
        dtype = np.dtype(dtype or np.float32)

        # two fields (ping-pong) and the curvature flow's one-channel weight
        def fits(shape):
            check_fits(
                self.runtime,
                shape,
                f"the {flow} flow",
                2 + (weight is not None) + 2 * (presmooth is not None),
                dtype=dtype,
            )

        data, self.layout = to_kernel_layout(image, channel_axis, fits=fits)
        nc, ny, nx = data.shape
        self.grid = Grid(self.runtime, nx, ny, nc, 1, dtype)
        self.flow = flow
        self.steps_done = 0
        self.time = 0.0
        self.pair = PingPong(Field.from_host(self.grid, data))
        self._setup(flow, dt, kappa, edge, eps, weight, presmooth)

    def _setup(self, flow, dt, kappa, edge, eps, weight, presmooth=None):
        g = self.grid
        self._smooth = None
        if flow == "heat":
            self.dt = check_time_step(dt, stability_limit(flow), "heat")
            kernel = g.kernel("planar/planar.cl", "planar_heat_step")
            self._extra = ()
        elif flow == "perona-malik":
            if edge not in ("exp", "rational"):
                raise InputError(f"edge must be 'exp' or 'rational', not {edge!r}")
            kappa = positive("kappa", kappa)
            self.dt = check_time_step(dt, stability_limit(flow), "Perona-Malik")
            kernel = g.kernel(
                "planar/planar.cl", "planar_perona_malik_step", EDGE_STOP=int(edge == "rational")
            )
            self._extra = (g.scalar(1.0 / kappa**2),)
            if presmooth is not None:
                # Catte et al.'s regularisation: the diffusivity from a smoothed copy
                import pyopencl.array as cla

                w = gaussian_weights(float(presmooth))
                self.presmooth_radius = len(w) - 1
                defines = {"EDGE_STOP": int(edge == "rational")}
                kernel = g.kernel("planar/catte.cl", "catte_perona_malik_step", **defines)
                self._smooth = (
                    g.kernel("planar/catte.cl", "catte_gauss_rows"),
                    g.kernel("planar/catte.cl", "catte_gauss_cols"),
                    cla.to_device(self.runtime.queue, w.astype(g.dtype)),
                    np.int32(len(w) - 1),
                    Field.empty(g),
                    Field.empty(g),
                )
        elif flow == "tv":
            eps = positive("eps", TV_EPS if eps is None else eps)
            self.dt = check_time_step(dt, stability_limit(flow, eps), f"TV (eps={eps:g})")
            kernel = g.kernel("planar/planar.cl", "planar_tv_step")
            self._extra = (g.scalar(eps * eps),)
        else:  # curvature
            eps = 1e-10 if eps is None else float(eps)
            self.dt = check_time_step(dt, stability_limit(flow), "curvature")
            if weight is None:
                kernel = g.kernel("planar/planar.cl", "planar_curvature_step")
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
                kernel = g.kernel("planar/planar.cl", "planar_curvature_step", HAS_WEIGHT=1)
            self._extra = (weight_buf, g.scalar(0), g.scalar(eps))
        self._kernel = kernel

    def _enqueue_step(self):
        g = self.grid
        if self.flow == "curvature":  # the weight buffer comes before dt
            args = (self._extra[0], g.scalar(self.dt), self._extra[2])
        else:
            args = (g.scalar(self.dt), *self._extra)
        if self._smooth is not None:
            rows, cols, w, radius, tmp, smooth = self._smooth
            g.launch(rows, self.pair.cur.data.data, tmp.data.data, w.data, radius)
            g.launch(cols, tmp.data.data, smooth.data.data, w.data, radius)
            g.launch(
                self._kernel,
                self.pair.cur.data.data,
                smooth.data.data,
                self.pair.nxt.data.data,
                *args,
            )
            self.pair.swap()
            self.steps_done += 1
            self.time += self.dt
            return
        g.launch(self._kernel, self.pair.cur.data.data, self.pair.nxt.data.data, *args)
        self.pair.swap()
        self.steps_done += 1
        self.time += self.dt

    def run(self, steps: int, progress: bool | None = None) -> PlanarFlow:
        """Enqueue `steps` steps; the host only waits to move the progress bar."""
        steps = check_steps(steps)
        bar = progress_bar(progress, steps, f"clpde {self.flow}", unit="step")
        chunk = 50
        with bar:
            for start in range(0, steps, chunk):
                for _ in range(min(chunk, steps - start)):
                    self._enqueue_step()
                if not bar.disable:
                    self.runtime.queue.finish()
                    bar.update(min(chunk, steps - start))
        return self

    def iterate(self, steps: int, every: int) -> Iterator[FlowState]:
        """Run `steps` steps, yielding a FlowState every `every` steps (and at the end)."""
        steps = check_steps(steps)
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


def diffuse(
    image: ArrayLike,
    flow: str = "heat",
    steps: int = 100,
    dt: float | None = None,
    channel_axis: int | None = None,
    device: str | int | None = None,
    *,
    progress: bool | None = None,
    dtype: DTypeLike | None = None,
    spacing: ArrayLike | None = None,
    return_info: bool = False,
    **params: ArrayLike | float | str,
) -> np.ndarray | tuple[np.ndarray, DiffuseInfo]:
    """Run a planar diffusion flow for `steps` explicit steps.

    Parameters
    ----------
    image : (rows, columns) or (rows, columns, channels) array
        Integer or float data, never modified; channels need `channel_axis`.
    flow : {'heat', 'perona-malik', 'tv', 'curvature'}
        'heat' (u_t = Lap u), 'perona-malik' (params kappa, edge='exp'|'rational' and
        presmooth: the regularised form of Catte et al., whose diffusivity reads the
        gradient of the image smoothed by a Gaussian of `presmooth` pixels, so that
        isolated noise spikes diffuse too; presmooth=0 is the plain flow),
        'tv' (u_t = div(grad u / |grad u|_eps), param eps, default TV_EPS = 0.005) or
        'curvature' (u_t = g kappa |grad u|, params weight=g, eps). Data is scaled to
        [0, 1] internally, so kappa and eps are in those units.
    steps : int
        Explicit time steps.
    dt : float, optional
        The time step; 0.8 of `stability_limit` by default, and a larger one than the
        limit is an error.
    channel_axis : int, optional
        The axis of the channels of a colour image, each diffused on its own.
    device : str or int, optional
        An OpenCL device ('cpu', 'gpu', an index or a name part; see `clpde.devices`).
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    dtype : {float32, float64}, optional
        The device's arithmetic (float32 by default).
    spacing : (3,) array_like, optional
        A volume's voxel size (z, y, x). (Z, Y, X) and (Z, Y, X, C) arrays are volumes
        (a 3-D array without channel_axis is one, and spacing makes any array one),
        diffused by `clpde.volumes` with heat, perona-malik (presmooth in spacing units),
        tv or curvature (eps only: no weight).
    return_info : bool
        Also return a `DiffuseInfo` (steps, dt, time reached, flow, stability limit).
    **params
        The flow's parameters named above; one that the flow does not take is an error.

    Returns
    -------
    ndarray, or (ndarray, DiffuseInfo) with return_info
        The result, with the input's shape and dtype.

    Raises
    ------
    InputError
        For bad images, an unknown flow, a parameter the flow does not take or an unstable
        time step, before any work.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> image = np.zeros((32, 32), np.uint8)
    >>> image[8:24, 8:24] = 200
    >>> smooth = clpde.diffuse(image, "heat", steps=20)
    >>> smooth.shape, smooth.dtype
    ((32, 32), dtype('uint8'))
    >>> centre, corner, outside = (int(smooth[p]) for p in ((16, 16), (8, 8), (16, 4)))
    >>> centre > 190, 0 < outside < corner < 100  # the square's edges blur outwards
    (True, True)
    """
    if is_volume(image, channel_axis, spacing):  # 3D: clpde/volumes/flows.py
        result, dt, limit = diffuse_volume(
            image, flow, steps, dt, channel_axis, device, spacing=spacing, progress=progress,
            dtype=dtype, **params,
        )  # fmt: skip
        info = DiffuseInfo(int(steps), dt, int(steps) * dt, flow, limit)
        return (result, info) if return_info else result
    unknown = sorted(set(params) - {p for names in FLOW_PARAMS.values() for p in names})
    if unknown:
        listed = "; ".join(f"{f}: {', '.join(p) or 'none'}" for f, p in FLOW_PARAMS.items())
        raise InputError(f"diffuse takes no parameter {unknown[0]!r}; the flows take ({listed})")
    if bounded.is_large(image) and flow in FLOWS:
        # one channel at a time, converted and restored in strips: the same numbers in a
        # fraction of the memory (diffuse_by_channel)
        _check_flow_params(flow, params)
        steps = check_steps(steps)
        result, state = diffuse_by_channel(
            image, flow, steps, dt, channel_axis, device, dtype, progress, params
        )
    else:
        state = PlanarFlow(
            image, flow, dt=dt, channel_axis=channel_axis, device=device, dtype=dtype, **params
        )
        result = state.run(steps, progress).result()
    if not return_info:
        return result
    eps = params.get("eps")
    limit = stability_limit(flow, TV_EPS if eps is None and flow == "tv" else (eps or 0.0))
    return result, DiffuseInfo(state.steps_done, state.dt, state.time, flow, limit)


# ---- large images: one channel at a time (bounded.py) --------------------------------------
def diffuse_by_channel(image, flow, steps, dt, channel_axis, device, precision, progress, params):
    """clpde.diffuse one channel at a time, converting and restoring in strips: bit for bit
    the whole-image result (every flow of planar.cl acts on each channel alone, with the
    same arithmetic per cell), in the memory of one channel's two device fields.
    Returns (result, the last channel's flow)."""

    runtime = get_runtime(device)
    dtype = np.dtype(precision or np.float32)
    shape = list(np.shape(image))
    if channel_axis is not None:
        del shape[channel_axis]
    # refused before the output or any strip is allocated, as the whole-image path does
    check_fits(runtime, (1, *shape[-2:]), f"the {flow} flow", 2, dtype=dtype)
    scaled = bounded.Scaled(image, channel_axis)
    grid = Grid(runtime, scaled.nx, scaled.ny, 1, 1, dtype)
    state = None
    for c in range(scaled.nc):
        padded = np.zeros(grid.padded_shape, dtype)
        for r in range(0, scaled.ny, bounded.STRIP_ROWS):
            rows = slice(r, min(r + bounded.STRIP_ROWS, scaled.ny))
            padded[0, 1 + rows.start : 1 + rows.stop, 1:-1] = scaled.block(rows, slice(None), c)[0]
        field = Field.empty(grid)
        field.data.set(padded)
        del padded
        field.fill_ghosts("neumann")
        state = _ChannelFlow(runtime, grid, PingPong(field), flow, dt, params)
        state.run(steps, progress=progress)
        out = state.pair.cur.data.get()[0, 1:-1, 1:-1]
        scaled.restore(out, slice(0, scaled.ny), slice(None), c)
        state.pair = None  # frees this channel's device fields before the next
    return scaled.out, state


class _ChannelFlow(PlanarFlow):
    """A PlanarFlow over one channel's field, already uploaded."""

    def __init__(self, runtime, grid, pair, flow, dt, params):
        self.runtime, self.grid, self.pair = runtime, grid, pair
        self.flow, self.steps_done, self.time = flow, 0, 0.0
        self._setup(
            flow,
            dt,
            params.get("kappa", 0.05),
            params.get("edge", "exp"),
            params.get("eps"),
            params.get("weight"),
            params.get("presmooth"),
        )
