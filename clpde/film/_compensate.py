"""Motion-compensated neighbours of a frame: flows, warped frames, validity, flicker gains."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ..imagedata import grow_mask
from ..motion.flow import FlowParams, FlowSolver, default_levels
from ._order import median_of

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/detect.cl",)

# A warped mask counts as clean below this (the warp spreads a bool mask over a rim).
_CLEAN = 0.01

# The film's flow, chosen on the calibration sequences of benchmarks/film.py: grain makes
# flat regions' data term noise, so a stronger smoothness than optical_flow's default; and
# fewer warps and sweeps, since each frame needs one flow per neighbour.
FILM_FLOW = FlowParams(alpha=0.25, warps=2, iterations=15)


@dataclass
class Neighbours:
    """K motion-compensated neighbours of frame t, as device stacks (K, ny, nx)."""

    offsets: list  # frame offsets k (neighbour t + k)
    grey: cla.Array  # warped grey (K, ny, nx)
    valid: cla.Array  # 1 inside the neighbour's frame (K, ny, nx)
    gain: np.ndarray  # (K,) flicker gain, neighbour -> frame t
    offset: np.ndarray  # (K,) flicker offset
    side: np.ndarray  # (K,) int32, -1 earlier / +1 later (the detector's two sides)
    colour: cla.Array | None = None  # warped planes (K, C, ny, nx)
    mask: cla.Array | None = None  # warped neighbour masks (K, ny, nx)


def fit_gain(g: np.ndarray, w: np.ndarray, ok: np.ndarray) -> tuple[float, float]:
    """(a, b) with g ~ a * w + b on the pixels `ok`: least squares, then again on the pixels
    within 2.5 robust deviations, so blotches and flow failures do not pull the fit. The
    line's least squares in closed form (covariance over variance), not a general solver."""
    gs, ws = g[ok][::3].astype(np.float64), w[ok][::3].astype(np.float64)
    if gs.size < 16 or ws.std() < 1e-6:
        return 1.0, 0.0
    a, b = 1.0, 0.0
    keep = None  # all, the first time
    for _ in range(2):
        wk, gk = (ws, gs) if keep is None else (ws[keep], gs[keep])
        mw, mg = wk.mean(), gk.mean()
        dw = wk - mw
        # numpy's own sums, not BLAS's dot: OpenBLAS splits a dot over its threads, which
        # costs ~15 ms of waking them per call on a busy 2-core machine (0.02 ms on one)
        # and makes the sum, so the film's result, depend on the thread count
        var = float(np.sum(dw * dw))
        a = float(np.sum(dw * (gk - mg))) / var if var > 0 else 1.0
        b = mg - a * mw
        res = gs - (a * ws + b)
        mad = 1.4826 * median_of(np.abs(res - median_of(res))) + 1e-6
        keep = np.abs(res) < 2.5 * mad
        if keep.sum() < 16:
            break
    a = float(np.clip(a, 0.5, 2.0))
    return a, float(b)


def match_moments(src: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """(a, b) so that a * src + b has ref's median and robust deviation (flicker is a
    gain and an offset per frame; medians keep dirt out of the fit)."""
    ms, mr = float(np.median(src)), float(np.median(ref))
    ds = float(np.median(np.abs(src - ms))) + 1e-6
    dr = float(np.median(np.abs(ref - mr))) + 1e-6
    a = float(np.clip(dr / ds, 0.5, 2.0))
    return a, mr - a * ms


class Compensator:
    """Device frames of one film and the flows between them."""

    def __init__(
        self,
        grey: np.ndarray,
        device=None,
        *,
        colour: np.ndarray | None = None,
        masks: np.ndarray | None = None,
        weights: np.ndarray | None = None,
        exclude: np.ndarray | None = None,
        params: FlowParams = FILM_FLOW,
    ):
        """grey (T, H, W) and colour (T, C, H, W) frames in [0, 1]; masks (T, H, W) the
        known damage (masked out of the flows, and warped with the neighbours), or weights
        (T, H, W) the flows' confidence alone (1 trusted, 0 ignored); exclude (T, H, W),
        pixels of each frame that may not serve as another frame's neighbour (its own
        suspected damage): warped with it and taken out of its validity."""
        self.solver = FlowSolver(device, params)
        self.rt = self.solver.rt
        q = self.q = self.rt.queue
        self.T, self.ny, self.nx = grey.shape
        self.host_grey = grey
        self.grey = [cla.to_device(q, np.ascontiguousarray(g)) for g in grey]
        self.colour = (
            None if colour is None else [cla.to_device(q, np.ascontiguousarray(c)) for c in colour]
        )
        self.masks = masks
        if masks is None:
            if weights is None:
                ones = cla.to_device(q, np.ones((self.ny, self.nx), np.float32))
                self.weights = [ones] * self.T
            else:
                self.weights = [
                    cla.to_device(q, np.ascontiguousarray(w, np.float32)) for w in weights
                ]
            self.mask_dev = None
        else:
            # the flow's confidence: zero on the damage and one pixel around it (the rim a
            # codec or a soft edge spreads)
            self.weights = [
                cla.to_device(q, (~grow_mask(m > 0, 1.0)).astype(np.float32)) for m in masks
            ]
            self.mask_dev = [cla.to_device(q, np.ascontiguousarray(m)) for m in masks]
        self.exclude = (
            None
            if exclude is None
            else [cla.to_device(q, np.ascontiguousarray(e, np.float32)) for e in exclude]
        )
        self.levels = default_levels(self.ny, self.nx)
        self.k_inside = self.rt.kernel("film/detect.cl", "detect_flow_inside")

    def _matched(self, s: int, t: int) -> cla.Array:
        """Frame s's grey with its mean and deviation matched to frame t's: flicker would
        otherwise read as motion wherever the image is flat."""
        a, b = match_moments(self.host_grey[s], self.host_grey[t])
        if abs(a - 1.0) < 1e-6 and abs(b) < 1e-7:
            return self.grey[s]
        return self.grey[s] * np.float32(a) + np.float32(b)

    def _put(self, stack, k, src):
        nbytes = src.nbytes
        cl.enqueue_copy(self.q, stack.data, src.data, dst_offset=k * nbytes, byte_count=nbytes)

    def neighbours(
        self, t: int, offsets: list[int], sides: list[int] | None = None, want_colour: bool = False
    ) -> Neighbours:
        q, ny, nx = self.q, self.ny, self.nx
        K = len(offsets)
        grey = cla.empty(q, (K, ny, nx), np.float32)
        valid = cla.empty(q, (K, ny, nx), np.float32)
        nc = self.colour[0].shape[0] if (want_colour and self.colour) else 0
        colour = cla.empty(q, (K, nc, ny, nx), np.float32) if nc else None
        wmask = cla.empty(q, (K, ny, nx), np.float32) if self.mask_dev is not None else None
        gains, offs = np.ones(K, np.float32), np.zeros(K, np.float32)
        g, loc = self.rt.items(nx, ny)
        for j, k in enumerate(offsets):
            s = t + k
            u, v = self.solver.flow(
                self.grey[t], self._matched(s, t), self.weights[t], self.weights[s], self.levels
            )
            wg = self.solver.warp(self.grey[s].reshape(1, ny, nx), u, v)
            self._put(grey, j, wg)
            inside = cla.empty(q, (ny, nx), np.float32)
            self.k_inside(q, g, loc, u.data, v.data, inside.data, np.int32(nx), np.int32(ny))
            if self.exclude is not None:
                ex = self.solver.warp(self.exclude[s].reshape(1, ny, nx), u, v)
                inside = cla.if_positive(
                    ex.reshape(ny, nx) - np.float32(_CLEAN), cla.zeros_like(inside), inside
                )
            self._put(valid, j, inside)
            if colour is not None:
                self._put(colour, j, self.solver.warp(self.colour[s], u, v))
            ok = inside.get() > 0.5
            if wmask is not None:
                wm = self.solver.warp(self.mask_dev[s].reshape(1, ny, nx), u, v)
                self._put(wmask, j, wm)
                ok &= (wm.get()[0] <= 0.01) & (self.masks[t] <= 0)
            gains[j], offs[j] = fit_gain(self.host_grey[t], wg.get()[0], ok)
        if sides is None:
            sides = [-1 if k < 0 else 1 for k in offsets]
        return Neighbours(
            list(offsets), grey, valid, gains, offs, np.asarray(sides, np.int32), colour, wmask
        )
