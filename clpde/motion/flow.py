"""Dense optical flow on the device, coarse to fine, with damaged pixels masked out.

The scheme (kernels/motion/flow.cl): a pyramid of confidence-weighted binomial halvings;
at each level, from the coarsest, a few warps; per warp the brightness constancy is
linearised about the current flow and the increment solved by red-black SOR with a robust
(Charbonnier) data term, weighted to zero on damaged pixels and where the warped place
leaves the frame, and a quadratic smoothness term, which fills the flow across the
damage from around it; a 3x3 median of the flow follows each warp.

Convention: ``flow[y, x] = (u, v)`` means ``frame1[y + v, x + u] ~ frame0[y, x]``; u is
along columns (x), v along rows (y), in pixels. ``warp(frame1, flow)`` is then an image
aligned with frame0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from numpy.typing import ArrayLike

from ..errors import InputError
from ..imagedata import as_image
from ..runtime import get_runtime

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("motion/flow.cl",)

# Coarsest level's shorter side at least this many pixels (default `levels`).
_COARSEST = 12


@dataclass(frozen=True)
class FlowParams:
    """The solver's parameters (see `optical_flow`)."""

    alpha: float = 0.03
    eps: float = 0.01
    warps: int = 4
    iterations: int = 30
    omega: float = 1.8
    median: bool = True


def default_levels(ny: int, nx: int) -> int:
    """Pyramid levels so that the coarsest level's shorter side is about 12 pixels."""
    side = min(ny, nx)
    levels = 1
    while side // 2 >= _COARSEST and levels < 8:
        side //= 2
        levels += 1
    return levels


def level_shapes(ny: int, nx: int, levels: int) -> list[tuple[int, int]]:
    """(ny, nx) per level, finest first: each level halves, rounding up."""
    shapes = [(ny, nx)]
    for _ in range(levels - 1):
        py, px = shapes[-1]
        shapes.append(((py + 1) // 2, (px + 1) // 2))
    return shapes


class FlowSolver:
    """The device side of `optical_flow`: kernels fetched once, buffers per image size.

    Film code keeps one and calls `flow` on device planes (float32 (ny, nx) pyopencl arrays
    in [0, 1]) so frames stay on the device between pairs.
    """

    def __init__(self, device=None, params: FlowParams | None = None):
        self.rt = get_runtime(device)
        self.params = params or FlowParams()
        k = self.rt.kernel
        self.k_down = k("motion/flow.cl", "flow_down")
        self.k_up = k("motion/flow.cl", "flow_up")
        self.k_lin = k("motion/flow.cl", "flow_linearise")
        self.k_sor = k("motion/flow.cl", "flow_sor")
        self.k_accept = k("motion/flow.cl", "flow_accept")
        self.k_median = k("motion/flow.cl", "flow_median3")
        self.k_warp = k("motion/flow.cl", "flow_warp_image")
        self._shape = None

    def _geometry(self, ny: int, nx: int, nc: int = 1):
        g, loc = self.rt.items(nx, ny, nc) if nc > 1 else self.rt.items(nx, ny)
        return g, loc

    def _pyramid(self, image, weight, shapes):
        q = self.rt.queue
        imgs, ws = [image], [weight]
        for (py, px), (cy, cx) in zip(shapes[:-1], shapes[1:], strict=True):
            di = cla.empty(q, (cy, cx), np.float32)
            dw = cla.empty(q, (cy, cx), np.float32)
            g, loc = self._geometry(cy, cx)
            self.k_down(
                q,
                g,
                loc,
                imgs[-1].data,
                ws[-1].data,
                di.data,
                dw.data,
                np.int32(px),
                np.int32(py),
                np.int32(cx),
                np.int32(cy),
            )
            imgs.append(di)
            ws.append(dw)
        return imgs, ws

    def flow(self, I0, I1, w0, w1, levels: int, init=None):
        """(u, v) device planes for device images I0, I1 and confidence weights w0, w1
        (1 clean, 0 damaged), all float32 (ny, nx); init (u, v) planes start the finest
        level instead of the pyramid's zero start when given."""
        q = self.rt.queue
        p = self.params
        ny, nx = I0.shape
        shapes = level_shapes(ny, nx, levels)
        P0, W0 = self._pyramid(I0, w0, shapes)
        P1, W1 = self._pyramid(I1, w1, shapes)
        u = v = None
        for lev in range(levels - 1, -1, -1):
            ly, lx = shapes[lev]
            g, loc = self._geometry(ly, lx)
            if u is None:
                u = cla.zeros(q, (ly, lx), np.float32)
                v = cla.zeros(q, (ly, lx), np.float32)
            else:
                uf = cla.empty(q, (ly, lx), np.float32)
                vf = cla.empty(q, (ly, lx), np.float32)
                cy, cx = shapes[lev + 1]
                self.k_up(
                    q,
                    g,
                    loc,
                    u.data,
                    v.data,
                    uf.data,
                    vf.data,
                    np.int32(cx),
                    np.int32(cy),
                    np.int32(lx),
                    np.int32(ly),
                )
                u, v = uf, vf
            if lev == 0 and init is not None:
                u, v = init[0].copy(), init[1].copy()
            du = cla.zeros(q, (ly, lx), np.float32)
            dv = cla.zeros(q, (ly, lx), np.float32)
            Ix, Iy, It, wd = (cla.empty(q, (ly, lx), np.float32) for _ in range(4))
            tmp = cla.empty(q, (ly, lx), np.float32)
            size = (np.int32(lx), np.int32(ly))
            for _ in range(p.warps):
                self.k_lin(
                    q,
                    g,
                    loc,
                    P0[lev].data,
                    P1[lev].data,
                    W0[lev].data,
                    W1[lev].data,
                    u.data,
                    v.data,
                    Ix.data,
                    Iy.data,
                    It.data,
                    wd.data,
                    *size,
                )
                for _ in range(p.iterations):
                    for parity in (0, 1):
                        self.k_sor(
                            q,
                            g,
                            loc,
                            Ix.data,
                            Iy.data,
                            It.data,
                            wd.data,
                            u.data,
                            v.data,
                            du.data,
                            dv.data,
                            np.float32(p.alpha**2),
                            np.float32(p.eps),
                            np.float32(p.omega),
                            np.int32(parity),
                            *size,
                        )
                self.k_accept(q, g, loc, u.data, v.data, du.data, dv.data, *size)
                if p.median:
                    for comp in (u, v):
                        self.k_median(q, g, loc, comp.data, tmp.data, *size)
                        cl.enqueue_copy(q, comp.data, tmp.data)
        return u, v

    def warp(self, src, u, v):
        """Device (nc, ny, nx) float32 image backward-warped by the device flow (u, v)."""
        q = self.rt.queue
        nc, ny, nx = src.shape
        out = cla.empty(q, src.shape, np.float32)
        g, loc = self.rt.items(nx, ny, nc)
        self.k_warp(q, g, loc, src.data, u.data, v.data, out.data, np.int32(nx), np.int32(ny))
        return out


def _grey_pair(frame0, frame1, channel_axis):
    a = as_image(frame0, "frame0")
    b = as_image(frame1, "frame1")
    if a.shape != b.shape:
        raise InputError(
            f"frame0 has shape {a.shape} but frame1 {b.shape}; give two frames of the same size"
        )
    if channel_axis is None:
        if a.ndim != 2:
            raise InputError(
                f"frames of {a.ndim} dimensions need channel_axis (e.g. "
                "channel_axis=-1 for (rows, columns, channels))"
            )
    else:
        if a.ndim != 3:
            raise InputError(
                f"channel_axis={channel_axis} needs (rows, columns, channels) "
                f"frames, got {a.ndim} dimensions"
            )
        a = np.moveaxis(a, channel_axis, -1)
        b = np.moveaxis(b, channel_axis, -1)
    if np.issubdtype(a.dtype, np.integer):
        info = np.iinfo(a.dtype)
        lo, span = float(info.min), float(info.max) - float(info.min)
    else:
        lo = float(min(a.min(), b.min()))
        span = float(max(a.max(), b.max())) - lo or 1.0
    g0 = (np.asarray(a, np.float64) - lo) / span
    g1 = (np.asarray(b, np.float64) - lo) / span
    if g0.ndim == 3:
        g0, g1 = g0.mean(axis=-1), g1.mean(axis=-1)
    return g0.astype(np.float32), g1.astype(np.float32)


def _weight(mask, shape, name):
    if mask is None:
        return np.ones(shape, np.float32)
    m = np.asarray(mask)
    if m.shape != shape:
        raise InputError(
            f"{name} has shape {m.shape} but the frames are {shape}; give one "
            "(rows, columns) mask per frame"
        )
    m = m.astype(np.float32)
    if not np.isfinite(m).all():
        raise InputError(f"{name} holds NaN or infinite values; give a bool or [0, 1] mask")
    return np.clip(1.0 - m, 0.0, 1.0).astype(np.float32)


def optical_flow(
    frame0: ArrayLike,
    frame1: ArrayLike,
    *,
    mask0: ArrayLike | None = None,
    mask1: ArrayLike | None = None,
    levels: int | None = None,
    channel_axis: int | None = None,
    alpha: float = 0.03,
    warps: int = 4,
    iterations: int = 30,
    device: str | int | None = None,
) -> np.ndarray:
    """Dense optical flow from frame0 to frame1, on the device, coarse to fine.

    The returned flow satisfies ``frame1[y + v, x + u] ~ frame0[y, x]`` with
    ``(u, v) = flow[y, x]``: u along columns, v along rows, in pixels; so
    ``warp(frame1, flow)`` is frame1 brought onto frame0. Pixels that ``mask0`` marks in
    frame0, or whose match ``mask1`` marks in frame1, carry no data weight: their flow is
    filled in by the smoothness term from the clean pixels around them, so dirt and
    scratches do not drag the motion.

    Parameters
    ----------
    frame0, frame1 : (rows, columns) or (rows, columns, channels) array
        Two frames of the same shape and dtype, never modified; colour is averaged to grey.
        Integer frames are scaled by their dtype's range, float frames by their joint range.
    mask0, mask1 : (rows, columns) array of bool or floats in [0, 1], optional
        Damage in each frame (True or 1 damaged).
    levels : int, optional
        Pyramid levels (default: halvings until the shorter side is about 12 pixels).
    channel_axis : int, optional
        The channel axis of colour frames.
    alpha : float
        Smoothness weight on the [0, 1] intensity scale; larger gives smoother flow.
    warps : int
        Re-linearisations per level.
    iterations : int
        Red-black SOR sweeps per warp.
    device : str or int, optional
        As for `clpde.diffuse`.

    Returns
    -------
    ndarray of float32, shape (rows, columns, 2)
        The flow (u, v) per pixel of frame0.

    Raises
    ------
    InputError
        Frames or masks of different shapes, frames with NaN, a bad parameter.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.motion import optical_flow
    >>> rng = np.random.default_rng(0)
    >>> from scipy.ndimage import gaussian_filter, shift
    >>> a = gaussian_filter(rng.random((64, 64)), 2.0)
    >>> b = shift(a, (1.0, 2.0), mode="nearest")  # b[y + 1, x + 2] = a[y, x]
    >>> flow = optical_flow(a, b)
    >>> [round(float(c), 1) for c in np.median(flow[16:-16, 16:-16], axis=(0, 1))]
    [2.0, 1.0]
    """
    g0, g1 = _grey_pair(frame0, frame1, channel_axis)
    ny, nx = g0.shape
    w0 = _weight(mask0, (ny, nx), "mask0")
    w1 = _weight(mask1, (ny, nx), "mask1")
    if levels is None:
        levels = default_levels(ny, nx)
    if not isinstance(levels, (int, np.integer)) or levels < 1:
        raise InputError(f"levels must be a positive integer, not {levels!r}")
    levels = int(levels)
    for name, val in (("warps", warps), ("iterations", iterations)):
        if not isinstance(val, (int, np.integer)) or val < 1:
            raise InputError(f"{name} must be a positive integer, not {val!r}")
    if not (np.isfinite(alpha) and alpha > 0):
        raise InputError(f"alpha must be a positive number, not {alpha!r}")
    solver = FlowSolver(
        device, FlowParams(alpha=float(alpha), warps=int(warps), iterations=int(iterations))
    )
    q = solver.rt.queue
    u, v = solver.flow(
        cla.to_device(q, g0),
        cla.to_device(q, g1),
        cla.to_device(q, w0),
        cla.to_device(q, w1),
        levels,
    )
    return np.stack([u.get(), v.get()], axis=-1).astype(np.float32)


def warp(
    image: ArrayLike,
    flow: ArrayLike,
    *,
    channel_axis: int | None = None,
    device: str | int | None = None,
) -> np.ndarray:
    """Backward-warp an image by a flow on the device: ``out[y, x] = image[y + v, x + u]``.

    Bicubic (Keys), with coordinates clamped to the image; with the flow `optical_flow` returns
    for (frame0, frame1), ``warp(frame1, flow)`` is aligned with frame0.

    Parameters
    ----------
    image : (rows, columns) or (rows, columns, channels) array
        Any channel count, never modified.
    flow : (rows, columns, 2) array
        (u, v) per output pixel, u along columns.
    channel_axis : int, optional
        The channel axis of a multichannel image.
    device : str or int, optional
        As for `clpde.diffuse`.

    Returns
    -------
    ndarray
        The warped image, the input's shape; float32 for float32 or integer input (integers
        are not rounded), float64 input gives float64 values computed in float32.

    Raises
    ------
    InputError
        A flow whose shape does not match the image, or NaN in either.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.motion import warp
    >>> img = np.arange(12, dtype=np.float32).reshape(3, 4)
    >>> flow = np.zeros((3, 4, 2), np.float32); flow[..., 0] = 1.0
    >>> warp(img, flow)[0].tolist()
    [1.0, 2.0, 3.0, 3.0]
    """
    arr = as_image(image, "image")
    if channel_axis is None:
        if arr.ndim != 2:
            raise InputError(f"a {arr.ndim}-D image needs channel_axis (e.g. -1)")
        planes = arr[np.newaxis]
    else:
        if arr.ndim != 3:
            raise InputError(
                f"channel_axis={channel_axis} needs a 3-D image, got {arr.ndim} dimensions"
            )
        planes = np.moveaxis(arr, channel_axis, 0)
    nc, ny, nx = planes.shape
    f = np.asarray(flow, dtype=np.float32)
    if f.shape != (ny, nx, 2):
        raise InputError(f"flow has shape {f.shape}; expected ({ny}, {nx}, 2) for this image")
    if not np.isfinite(f).all():
        raise InputError("flow holds NaN or infinite values")
    solver = FlowSolver(device)
    q = solver.rt.queue
    src = cla.to_device(q, np.ascontiguousarray(planes, np.float32))
    out = solver.warp(
        src,
        cla.to_device(q, np.ascontiguousarray(f[..., 0])),
        cla.to_device(q, np.ascontiguousarray(f[..., 1])),
    ).get()
    out = out[0] if channel_axis is None else np.moveaxis(out, 0, channel_axis)
    return out.astype(np.float64) if arr.dtype == np.float64 else out
