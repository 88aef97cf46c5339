"""Image inpainting by transport of smoothness along isophotes (thesis chapter 3, appendix A).

Inside the region Omega to fill, the image evolves by eqs. (3.5)-(3.11),

    I_t = (delta L . N / |N|) |grad I|_limited,   L = Lap I,   N = grad-perp I,

so that the Laplacian (the "smoothness") is carried along the isophotes arriving at the
border of Omega; every A = 15 such steps, B = 2 steps of anisotropic diffusion (3.4),
I_t = g_eps kappa |grad I|, keep the isophotes from crossing. At the steady state the
Laplacian is constant along isophotes.

How this implementation runs it (all on the OpenCL device):

- Methods: `method=` picks one of clpde.inpainting's modules (this scheme is "transport");
  the dispatch, the boxes and the soft masks below are shared by all of them.
- Boxes: each connected component of the mask, or cluster of nearby components, is solved
  in its own box, its bounding box grown by the method's margin (clpde/inpainting/boxes.py);
  only the box is converted to float, so time and memory follow the damage. The output
  is one copy of the input, written in place, box by box.
- The data is scaled to [0, 1] (the transport term grows with the square of the intensity).
- The box is first smoothed by a few steps of anisotropic diffusion, so that noise does not
  steer the isophote directions (section 3.3.3).
- Start inside Omega: the biharmonic fill on the coarsest level, which matches the border's
  values and slopes; `fill="diffusion"` is the harmonic fill (the steady state of the heat
  equation in Omega with the known pixels as boundary values, iterated on the device). Each
  finer level starts from the upsampled result of the coarser one plus the extension of its
  mismatch with the known border (no seams). A smooth start that already matches the
  border cuts the number of steps several-fold compared with a constant start, and on
  photos, where the best PSNR comes long before the steady state, the biharmonic start is
  worth 0.3-0.5 dB (benchmarks/inpaint_quality.py).
- The derivatives of N and delta L are Scharr's (stencil="isotropic"); appendix A's central
  differences (stencil="central") are not isotropic enough for sharp oblique isophotes
  (docs/inpainting.md has the experiments).
- Index lists, built on the device once per level, restrict the work to Omega-epsilon: the
  transport updates Omega only (its stencil, with the Laplacian at the neighbours, reads
  known pixels up to two cells outside), the diffusion runs where g_eps > 0 (g_eps = 1 in
  Omega, falling as a cosine to 0 at distance epsilon from Omega). Known pixels next to
  Omega feed the boundary; after each diffusion batch the known pixels of the band are
  reset, so values outside Omega never drift.
- Soft masks (a float mask, the degree of damage m in [0, 1]): after every cycle, a pixel
  of Omega is moved (1 - m) of the way back to its observed value.
- Every `check_every` cycles the largest and the mean change inside Omega are reduced on the
  device; the run stops once the largest falls below `tol` or the mean below `mean_tol` (or
  after `max_steps`). The mean test is the one that ends runs on photos, where a few pixels
  never settle (see `inpaint`'s docstring).
- Multiresolution: one level for thin masks (half-width up to 8 px), two for thicker ones
  (multiresolution.auto_levels has the measurements).
- The output equals the input bit for bit outside the mask.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from numpy.typing import ArrayLike, DTypeLike
from scipy import ndimage

from . import multiresolution as mr
from ._progress import Progress, progress_bar
from ._state import DeviceLike, State, deprecated, renamed_keyword
from ._validation import positive
from .colour import rgb_to_rho_phi_psi, rho_phi_psi_to_rgb
from .fields import Field, Grid, PingPong, check_fits, index_list
from .imagedata import (
    ImageLayout,
    InputError,
    as_image,
    check_channel_axis,
    compute_dtype,
    integer_range,
    value_range,
)
from .runtime import ClpdeError, get_runtime

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("fields.cl", "inpaint.cl", "planar.cl")

SCALINGS = ("none", "quartic-root")
COLOUR_MODELS = ("channels", "rho-phi-psi")
ROTATIONS = ("ccw", "cw")
FILLS = ("diffusion", "biharmonic", "mean", "zero")
STENCILS = ("central", "isotropic")
COARSE_STARTS = ("corrected", "upsampled")
GHOST = 2  # ghost layers: the transport stencil reaches two cells


@dataclass
class InpaintState(State):
    """One intermediate state: the whole image (in the input's layout and dtype)."""

    level: int  # 0 is the finest
    step: int  # steps taken on this level so far
    image: np.ndarray
    change: float | None = None  # largest change in Omega over the last check interval

    @property
    def time(self) -> None:
        """None: inpainting mixes transport and diffusion steps, it has no single time."""
        return None


@dataclass
class InpaintInfo:
    """What a run did. `steps` counts transport plus diffusion steps on the finest level."""

    steps: int
    converged: bool
    levels: int
    steps_per_level: list = field(default_factory=list)  # fine to coarse
    omega_pixels: int = 0
    band_pixels: int = 0
    seconds: float = 0.0
    snapshots: list = field(default_factory=list)
    method: str = "transport"
    boxes: list = field(default_factory=list)  # (y0, y1, x0, x1) of each box solved
    box_methods: list = field(default_factory=list)  # the method that solved each box
    # omega pixels of each box that the exemplar filled (under method="auto" a box named
    # "<structure>+exemplar" had only its thick parts refilled by the exemplar)
    box_exemplar_pixels: list = field(default_factory=list)


@dataclass(frozen=True)
class InpaintParams:
    dt: float = 0.1
    transport_steps: int = 15  # A
    diffusion_steps: int = 2  # B
    diffusion_dt: float = 0.1  # the thesis' speed; appendix A's code uses 0.2
    epsilon: float = 3.0
    presmooth: int = 1
    scaling: str = "none"
    rotation: str = "ccw"
    max_steps: int = 3000
    tol: float = 1e-4  # on the largest change in Omega over a check interval
    mean_tol: float = 4e-4  # on the mean change in Omega over a check interval
    check_every: int = 2  # cycles of A + B steps
    fill: str = "biharmonic"
    keep_band: bool = True
    stencil: str = "isotropic"
    coarse_start: str = "corrected"


# ---------------------------------------------------------------------------------------
# Input handling


def _as_mask(mask, shape_hw):
    """(omega, softness): omega is a bool (rows, cols) array, True where anything is to be
    filled; softness is None for a binary mask, else the float degree of damage in [0, 1].
    A bool mask is used as is (no copy)."""
    m = np.asarray(mask)
    if m.dtype != bool and not (np.issubdtype(m.dtype, np.number)):
        raise InputError(f"mask has dtype {m.dtype}; give a bool or numeric array (nonzero = "
                         "inpaint)")
    if m.ndim == 3 and m.shape[-1] == 1:
        m = m[..., 0]
    if m.shape != tuple(shape_hw):
        raise InputError(
            f"mask shape {m.shape} does not match the image's height and width {tuple(shape_hw)}; "
            "give a (rows, columns) mask of the same size as the image"
        )
    if m.dtype == bool:
        return m, None
    if not np.issubdtype(m.dtype, np.floating):
        return m != 0, None
    lo, hi = m.min(), m.max()  # NaN propagates into both
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise InputError("mask contains NaN or infinite values; a float mask is the degree of "
                         "damage in [0, 1] (0 keep, 1 inpaint)")
    if lo < 0 or hi > 1:
        raise InputError(f"float mask values lie in [{lo:g}, {hi:g}], outside [0, 1]; a float mask "
                         "is the degree of damage (0 keep, 1 inpaint): rescale it, or pass a bool "
                         "mask (mask != 0)")
    omega = m > 0
    soft = bool(((m > 0) & (m < 1)).any())
    return omega, (m if soft else None)


def _prepare(image, mask, channel_axis, alpha):
    """(array, planes view (nc, ny, nx), omega, softness, layout, alpha): validation and the
    [0, 1] scaling, without a float copy of the image (boxes are converted one at a time)."""
    array = as_image(image, allow_nan=True)
    axis = check_channel_axis(array.ndim, channel_axis)
    planes = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
    floating = np.issubdtype(array.dtype, np.floating)
    finite = np.isfinite(planes).all(axis=0) if floating else None
    softness = None
    if mask is None:
        if finite is None:
            raise InputError(
                "mask=None fills the NaN pixels of a float image, but this image is "
                f"{array.dtype}; "
                "pass a mask (nonzero where to inpaint)"
            )
        omega = ~finite
    else:
        omega, softness = _as_mask(mask, planes.shape[1:])
        if finite is not None and not finite[~omega].all():
            raise InputError(
                f"image has {int((~finite[~omega]).sum())} NaN or infinite pixels outside the "
                "mask; "
                "include them in the mask, or pass mask=None to fill every NaN pixel"
            )
        partly = None if softness is None else (softness > 0) & (softness < 1)
        if partly is not None and finite is not None and not finite[partly].all():
            raise InputError("image has NaN or infinite pixels where the soft mask is below 1; "
                             "a partly damaged pixel needs its observed value (set the mask to 1 "
                             "there)")
    nc = planes.shape[0]
    if alpha is None:
        alpha = axis is not None and nc == 4
    if alpha and nc < 2:
        raise InputError("alpha=True needs at least two channels (the last one is the alpha)")
    if alpha and finite is not None and not np.isfinite(planes[-1]).all():
        raise InputError(
            "the alpha channel (the last one) holds NaN or infinite values, and only the colour "
            "channels are inpainted; fix the alpha channel first, or pass alpha=False"
        )
    if np.issubdtype(array.dtype, np.integer):
        offset, scale = integer_range(array.dtype)
    else:
        where = finite & ~omega if omega.any() and not omega.all() else finite
        if where.any():
            lo = float(np.min(planes, where=where[None], initial=np.inf))
            hi = float(np.max(planes, where=where[None], initial=-np.inf))
        else:
            lo, hi = 0.0, 1.0
        offset, scale = value_range(lo, hi)
    layout = ImageLayout(array.shape, array.dtype, axis, offset, scale)
    return array, planes, omega, softness, layout, bool(alpha)


def _check_params(p: InpaintParams, ncolour: int, colour: str) -> None:
    positive("dt", p.dt)
    positive("diffusion_dt", p.diffusion_dt)
    if p.diffusion_dt > 0.25:
        raise InputError(
            f"diffusion_dt={p.diffusion_dt:g} is beyond the stability limit 0.25 of the explicit "
            "curvature diffusion; use diffusion_dt <= 0.25"
        )
    if p.epsilon < 2:
        raise InputError(
            f"epsilon={p.epsilon:g} is too small: the transport stencil reaches two pixels past "
            "Omega, so epsilon must be at least 2"
        )
    for name in ("transport_steps", "diffusion_steps", "presmooth", "max_steps", "check_every"):
        v = getattr(p, name)
        low = 1 if name in ("transport_steps", "check_every") else 0
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
            raise InputError(f"{name} must be an integer >= {low}, not {v!r}")
    for name in ("tol", "mean_tol"):
        v = getattr(p, name)
        if not np.isfinite(v) or v < 0:
            raise InputError(f"{name} must be a number >= 0, not {v}")
    if p.scaling not in SCALINGS:
        raise InputError(f"scaling must be one of {', '.join(SCALINGS)}, not {p.scaling!r}")
    if p.rotation not in ROTATIONS:
        raise InputError(f"rotation must be 'ccw' or 'cw', not {p.rotation!r}")
    if p.coarse_start not in COARSE_STARTS:
        raise InputError(f"coarse_start must be one of {', '.join(COARSE_STARTS)}, not "
                         f"{p.coarse_start!r}")
    if p.stencil not in STENCILS:
        raise InputError(f"stencil must be one of {', '.join(STENCILS)}, not {p.stencil!r}")
    if p.fill not in FILLS:
        raise InputError(f"fill must be one of {', '.join(FILLS)}, not {p.fill!r}")
    _check_colour(colour, ncolour)


def _check_colour(colour: str, ncolour: int) -> None:
    if colour not in COLOUR_MODELS:
        raise InputError(f"colour must be one of {', '.join(COLOUR_MODELS)}, not {colour!r}")
    if colour == "rho-phi-psi" and ncolour != 3:
        raise InputError(
            f"colour='rho-phi-psi' needs 3 colour channels (R, G, B), the image has {ncolour}; "
            "use colour='channels'"
        )


# ---------------------------------------------------------------------------------------
# One resolution level on the device


class LevelSolver:
    """The inpainting loop on one resolution level; the state stays on the device."""

    def __init__(self, runtime, data: np.ndarray, omega: np.ndarray, params: InpaintParams,
                 dtype=np.float32, fidelity: np.ndarray | None = None, observed=None):
        self.p = params
        nc, ny, nx = data.shape
        self.grid = g = Grid(runtime, nx, ny, nc, GHOST, np.dtype(dtype))
        self.q = runtime.queue
        self.omega = omega

        dist = ndimage.distance_transform_edt(~omega)  # 0 in Omega
        weight = np.where(dist < params.epsilon, 0.5 * (1 + np.cos(np.pi * dist / params.epsilon)),
                          0)
        band = weight > 0
        self.omega_list = index_list(g, omega)
        self.band_list = index_list(g, band)
        # The known part of the band: diffusion may move it during a cycle (g_eps > 0 there),
        # but it is reset afterwards, so pixels outside Omega keep their values.
        self.ring_list = index_list(g, band & ~omega)

        def touches_border(m):
            return bool(m[0].any() or m[-1].any() or m[:, 0].any() or m[:, -1].any())

        # Ghosts only matter when the band comes within two cells of the image border (the
        # transport stencil's reach); otherwise they are never read and are not refilled.
        self.ghosts = touches_border(ndimage.binary_dilation(band, np.ones((3, 3), bool)))
        self.ghost_pairs = self._ghost_pairs(band) if self.ghosts else None
        self.pair = PingPong(Field.from_host(g, data))
        self.prev = self.pair.cur.copy()
        self.known = self.pair.cur.copy()
        self.weight = Field.from_host(Grid(runtime, nx, ny, 1, GHOST, g.dtype), weight[None])

        self.k_fill = g.kernel("inpaint.cl", "inpaint_fill")
        self.k_copy = g.kernel("fields.cl", "copy_listed")  # keeps the pair equal off a list
        self.k_change = g.kernel("inpaint.cl", "inpaint_max_change")
        self.k_sum_change = g.kernel("inpaint.cl", "inpaint_sum_change")
        self.k_ghosts = g.kernel("inpaint.cl", "inpaint_ghosts")
        # Soft masks: pixels of Omega with fidelity w > 0 are drawn back towards their
        # observed value by w after every cycle.
        self.fidelity = None
        if fidelity is not None and (fidelity > 0).any():
            self.fidelity_list = index_list(g, fidelity > 0)
            self.fidelity = Field.from_host(Grid(runtime, nx, ny, 1, GHOST, g.dtype),
                                            fidelity[None])
            self.observed = Field.from_host(g, observed)
            self.k_fidelity = g.kernel("inpaint.cl", "inpaint_fidelity")
        self.sx = np.int32(g.sx)
        self.rot = g.scalar(1.0 if params.rotation == "ccw" else -1.0)
        self.steps = 0
        self._bind_step_kernels(runtime, params)

    def _bind_step_kernels(self, runtime, params) -> None:
        """Kernel instances with every argument set, one per ping-pong direction: a step is
        then a bare enqueue (pyopencl's argument handling costs ~0.1 ms per call, as much as
        a step's work on a small region)."""
        g = self.grid
        defines = {"SCALING": SCALINGS.index(params.scaling),
                   "STENCIL": STENCILS.index(params.stencil)}
        bufs = (self.pair.cur.data.data, self.pair.nxt.data.data)
        self._buf_a = bufs[0]

        def bound(kernel, lst, *args):
            (gsize,), (lsize,), run = runtime.list_launch(max(lst.n, 1))
            kernel.set_args(*args, lst.indices.data, np.int32(lst.n), np.int32(g.plane),
                            np.int32(run))
            return kernel, (gsize, g.nc), (lsize, 1), lst.n

        def ghosts(buf):
            if not self.ghosts:
                return None
            kernel = runtime.new_kernel("inpaint.cl", "inpaint_ghosts", g.dtype, **defines)
            n = self.ghost_pairs.shape[0]
            kernel.set_args(buf, self.ghost_pairs.data, np.int32(n), np.int32(g.plane))
            return kernel, *runtime.items(n, g.nc), n

        dt, eps = g.scalar(params.dt), g.scalar(1e-10)
        ddt = g.scalar(params.diffusion_dt)
        self._steps = {}
        for src, dst in (bufs, bufs[::-1]):
            self._steps[("transport", src.int_ptr)] = (
                bound(runtime.new_kernel("inpaint.cl", "inpaint_transport", g.dtype, **defines),
                      self.omega_list, src, dst, dt, self.rot, eps, self.sx),
                ghosts(dst))
            self._steps[("diffusion", src.int_ptr)] = (
                bound(runtime.new_kernel("inpaint.cl", "inpaint_diffusion", g.dtype, **defines),
                      self.band_list, src, dst, self.weight.data.data, ddt,
                      eps, self.sx),
                ghosts(dst))

    def _enqueue_step(self, name: str) -> None:
        """One bound step from the current buffer into the other, ghosts refreshed, swap."""
        step, ghosts = self._steps[(name, self.pair.cur.data.data.int_ptr)]
        for launch in (step, ghosts):
            if launch is not None and launch[3] > 0:
                cl.enqueue_nd_range_kernel(self.q, launch[0], launch[1], launch[2])
        self.pair.swap()

    def _ghost_pairs(self, active: np.ndarray) -> cla.Array:
        """(ghost, source) padded indices of the ghosts within reach of active cells; the
        source mirrors the ghost across the border face, as Field.fill_ghosts does."""
        g = self.grid
        ny, nx = active.shape
        padded = np.pad(active, GHOST)
        reach = ndimage.binary_dilation(padded, np.ones((2 * GHOST + 1,) * 2, bool))
        reach[GHOST:-GHOST, GHOST:-GHOST] = False  # keep the ghost frame only
        gy, gx = np.nonzero(reach)

        def mirror(p, size):
            q = p - GHOST
            q = np.where(q < 0, -1 - q, np.where(q >= size, 2 * size - 1 - q, q))
            return np.clip(q, 0, size - 1) + GHOST

        pairs = np.stack([gy * g.sx + gx, mirror(gy, ny) * g.sx + mirror(gx, nx)], axis=1)
        return cla.to_device(self.q, pairs.astype(np.int32))

    def _fill_ghosts(self, field: Field) -> None:
        if self.ghosts:
            n = self.ghost_pairs.shape[0]
            self.k_ghosts(self.q, *self.grid.runtime.items(n, self.grid.nc), field.data.data,
                          self.ghost_pairs.data, np.int32(n), np.int32(self.grid.plane))

    # -- building blocks ---------------------------------------------------------------
    def _finish_step(self, field: Field) -> None:
        self._fill_ghosts(field)
        self.pair.swap()

    def _sync(self, lst) -> None:
        """Make nxt equal cur on a list, so the pair agrees everywhere."""
        self.grid.launch_list(self.k_copy, lst, self.pair.cur.data.data, self.pair.nxt.data.data)

    def transport_step(self) -> None:
        self._enqueue_step("transport")

    def diffusion_step(self) -> None:
        self._enqueue_step("diffusion")

    def presmooth(self, steps: int) -> None:
        """Anisotropic diffusion of the whole image (planar.cl's curvature step)."""
        g = self.grid
        kernel = g.kernel("planar.cl", "curvature_step")
        for _ in range(steps):
            g.launch(kernel, self.pair.cur.data.data, self.pair.nxt.data.data,
                     self.pair.cur.data.data, g.scalar(self.p.diffusion_dt), g.scalar(1e-10))
            self.pair.nxt.fill_ghosts()
            self.pair.swap()
        if steps:
            self.pair.nxt.assign(self.pair.cur)
        self.known.assign(self.pair.cur)

    def harmonic_fill(self, iterations: int) -> None:
        for _ in range(iterations):
            self.grid.launch_list(self.k_fill, self.omega_list, self.pair.cur.data.data,
                                  self.pair.nxt.data.data, self.sx)
            self._finish_step(self.pair.nxt)
        self._sync(self.omega_list)

    def max_change(self) -> float:
        """Largest |cur - prev| in Omega (a device reduction; a few numbers come back)."""
        g, lst = self.grid, self.omega_list
        (gsize,), _, _ = g.runtime.list_launch(lst.n)
        partial = cla.empty(self.q, (g.nc, gsize), g.dtype)
        g.launch_list(self.k_change, lst, self.pair.cur.data.data, self.prev.data.data,
                      partial.data)
        return float(partial.get().max())

    def mean_change(self) -> float:
        """Mean |cur - prev| over Omega and the channels (device partial sums)."""
        g, lst = self.grid, self.omega_list
        (gsize,), _, _ = g.runtime.list_launch(lst.n)
        partial = cla.empty(self.q, (g.nc, gsize), g.dtype)
        g.launch_list(self.k_sum_change, lst, self.pair.cur.data.data, self.prev.data.data,
                      partial.data)
        return float(partial.get().astype(np.float64).sum()) / max(lst.n * g.nc, 1)

    def cycle(self) -> None:
        """A transport steps, then B diffusion steps."""
        for _ in range(self.p.transport_steps):
            self.transport_step()
        for _ in range(self.p.diffusion_steps):
            self.diffusion_step()
        if self.p.diffusion_steps:
            if self.p.keep_band:
                self.grid.launch_list(self.k_copy, self.ring_list, self.known.data.data,
                                      self.pair.cur.data.data)
                self._fill_ghosts(self.pair.cur)
            self._sync(self.band_list)
        self.apply_fidelity()
        self.steps += self.p.transport_steps + self.p.diffusion_steps

    def apply_fidelity(self) -> None:
        if self.fidelity is not None:
            self.grid.launch_list(self.k_fidelity, self.fidelity_list, self.pair.cur.data.data,
                                  self.pair.nxt.data.data, self.observed.data.data,
                                  self.fidelity.data.data)

    def run(self, max_steps: int, tol: float, mean_tol: float = 0.0):
        """Cycle until converged or max_steps; yields (steps, change) after every check
        (change: the largest change in Omega). Converged: the largest change is below
        `tol`, or the mean change below `mean_tol`; `self.converged` tells."""
        p = self.p
        self.prev.assign(self.pair.cur)
        cycles = 0
        self.converged = False
        while self.steps < max_steps:
            self.cycle()
            cycles += 1
            if cycles % p.check_every == 0:
                change = self.max_change()
                if not np.isfinite(change) or change > 1e3:
                    raise ClpdeError(
                        f"the inpainting diverged after {self.steps} steps (change {change:g}); "
                        "use a smaller dt or more diffusion_steps"
                    )
                self.converged = change < tol or (mean_tol > 0 and self.mean_change() < mean_tol)
                yield self.steps, change
                if self.converged:
                    return
                self.grid.launch_list(self.k_copy, self.omega_list, self.pair.cur.data.data,
                                      self.prev.data.data)
        yield self.steps, None

    def result(self) -> np.ndarray:
        return self.pair.cur.to_host().astype(np.float64)


# ---------------------------------------------------------------------------------------
# method="transport" on one box: the levels, coarse to fine


# InpaintParams' fields that `inpaint` names in its signature (the others go in **options),
# in the fields' order
_TRANSPORT_ARGS = ("dt", "transport_steps", "diffusion_steps", "diffusion_dt", "epsilon",
                   "presmooth", "scaling", "rotation", "max_steps", "tol", "mean_tol",
                   "check_every", "fill", "keep_band")


def transport_params(params: dict) -> InpaintParams:
    unknown = set(params) - set(InpaintParams.__dataclass_fields__)
    if unknown:
        raise InputError(f"unknown inpainting option(s): {', '.join(sorted(unknown))}")
    return InpaintParams(**params)


class TransportRun:
    """The thesis's scheme on (nc, ny, nx) data in [0, 1]: the pyramid, the start on the
    coarsest level, one LevelSolver per level. `states(every)` yields (steps, change, data)
    on the finest level; afterwards `solution` and the counters are set."""

    def __init__(self, runtime, data, omega, params, *, levels=None, dtype=np.float32,
                 progress=None, fidelity=None):
        self.p = params if isinstance(params, InpaintParams) else transport_params(params)
        self.runtime, self.data, self.omega = runtime, data, omega
        self.device = runtime  # get_runtime(self.device) is this runtime
        self.levels = levels if levels is not None else mr.auto_levels(omega)
        self.dtype, self.progress, self.fidelity = dtype, progress, fidelity
        self.solution = None
        self.steps = 0
        self.steps_per_level = []
        self.converged = False
        self.band_pixels = 0

    def states(self, every=None):
        p = self.p
        levels = mr.pyramid(self.data, self.omega, self.levels)
        self.steps_per_level = [0] * len(levels)
        bar = progress_bar(self.progress, p.max_steps * len(levels), "clpde inpaint", unit="step")
        solution = None
        with bar:
            for level in range(len(levels) - 1, -1, -1):
                data, omega = levels[level]
                observed = data
                data = data.copy()
                if solution is None:
                    start_values = self._start_values(data, omega)
                elif p.coarse_start == "corrected":
                    # The upsampled coarse result misses the fine border values by up to a
                    # coarse pixel's variation, which leaves seams; the mismatch on the known
                    # pixels is extended into Omega (as the start is) and added back.
                    start_values = mr.upsample(solution, omega.shape)
                    mismatch = np.where(omega, 0.0, data - start_values)
                    start_values = start_values + self._start_values(mismatch, omega)
                else:
                    start_values = mr.upsample(solution, omega.shape)
                data[:, omega] = start_values[:, omega]
                finest = level == 0
                # the fidelity of a soft mask acts on the finest level, where it is observed
                fidelity = self.fidelity if finest else None
                solver = LevelSolver(self.runtime, data, omega, p, self.dtype, fidelity, observed)
                solver.presmooth(p.presmooth)  # also records the known values (solver.known)
                if solution is None and p.fill == "diffusion":
                    width = mr.hole_half_width(omega)
                    solver.harmonic_fill(int(np.clip(4 * width * width, 20, 4000)))
                solver.apply_fidelity()
                if finest and every:
                    yield 0, None, solver.result()
                last_yield = 0
                done = 0
                for steps, change in solver.run(p.max_steps, p.tol, p.mean_tol):
                    bar.update(steps - done)
                    done = steps
                    if solver.converged and finest:
                        self.converged = True
                    if finest and every and steps - last_yield >= every:
                        last_yield = steps
                        yield steps, change, solver.result()
                bar.update(p.max_steps - done)
                self.steps_per_level[level] = solver.steps
                solution = solver.result()
                if finest:
                    self.steps, self.band_pixels = solver.steps, solver.band_list.n
        self.levels = len(levels)
        out = self.data.copy()
        out[:, self.omega] = solution[:, self.omega]
        self.solution = out

    def _start_values(self, data, omega):
        known = ~omega
        fill = self.p.fill
        if fill == "mean":
            return np.broadcast_to(data[:, known].mean(axis=1)[:, None, None], data.shape)
        if fill == "zero":
            return np.zeros_like(data)
        if fill == "biharmonic":
            from .inpainting import poisson  # conjugate gradients on the device

            return poisson.fill(data, omega, get_runtime(self.device), "biharmonic",
                                dtype=self.dtype)
        # "diffusion": begin the Jacobi iterations from the nearest known value, which is
        # already close to the harmonic fill of a thin region.
        _, (iy, ix) = ndimage.distance_transform_edt(omega, return_indices=True)
        return data[:, iy, ix]


# ---------------------------------------------------------------------------------------
# The public object form and function


class Inpainting:
    """Inpainting whose intermediate states can be watched.

    The keyword arguments are those of `inpaint` (its docstring has them and the return
    shapes). Intermediate states come from method="transport" only; other methods yield
    their start and their result.

    Examples
    --------
    >>> import numpy as np
    >>> ramp = np.tile(np.linspace(0, 1, 32, dtype=np.float32), (32, 1))
    >>> mask = np.zeros((32, 32), bool)
    >>> mask[12:20, 12:20] = True
    >>> job = Inpainting(ramp, mask, method="transport")
    >>> steps = [state.step for state in job.iterate(every=50)]   # show(state.image) ...
    >>> steps[0] < steps[-1], job.result.shape, job.info.converged
    (True, (32, 32), True)
    """

    def __init__(self, image: ArrayLike, mask: ArrayLike | None = None, *,
                 channel_axis: int | None = None, alpha: bool | None = None,
                 colour: str = "channels", levels: int | None = None, device: DeviceLike = None,
                 dtype: DTypeLike | None = None, progress: Progress = None,
                 method: str | None = None, boxes: bool = True, seed: int | None = None,
                 precision: DTypeLike | None = None, **params: Any):
        from . import inpainting

        self.image, self.planes, self.mask, self.softness, self.layout, self.alpha = _prepare(
            image, mask, channel_axis, alpha)
        ncolour = self.planes.shape[0] - int(self.alpha)
        _check_colour(colour, ncolour)
        if self.mask.all():
            raise InputError(
                "the mask covers every pixel, so nothing is known to inpaint from; "
                "mark only the damaged region"
            )
        if levels is not None and (isinstance(levels, bool) or not isinstance(levels,
                                                                              (int, np.integer))
                                   or levels < 1):
            raise InputError(f"levels must be an integer >= 1 or None (automatic), not {levels!r}")
        given = {**params, **({} if levels is None else {"levels": levels})}
        self.method = choose_method(self.mask, method, given)
        # "auto" picks per box between this structure method and the exemplar
        # (inpainting/choose.py); the options given are the structure method's.
        self.auto = choose_method(self.mask, method, given, per_box=True) == "auto" and \
            "exemplar" in inpainting.available()
        if self.method == "transport":
            self.p = transport_params(params)
            _check_params(self.p, ncolour, colour)
            if levels is not None:
                params = dict(params, levels=levels)
        else:
            self.p = None
            if levels is not None:
                params = dict(params, levels=levels)
            inpainting.check_params(self.method, self.module, params)
        self.params = params
        self.boxes = bool(boxes)
        self.seed = seed
        self.colour = colour
        self.ncolour = ncolour
        self.levels = levels
        self.device = device
        self.dtype = compute_dtype(None, renamed_keyword("dtype", dtype, "precision", precision))
        self.progress = progress
        self.result = None
        self.info = None

    @property
    def module(self):
        """The method's module (looked up, not stored, so that the object pickles)."""
        from . import inpainting

        return inpainting.load(self.method)

    # -- conversions between the user's image and the solved channels -----------------
    def _box_data(self, box):
        """The box's channels as float64 in [0, 1] (NaN -> 0), colour model applied."""
        y0, y1, x0, x1 = box
        part = self.planes[: self.ncolour, y0:y1, x0:x1]
        data = (part.astype(np.float64) - self.layout.offset) / self.layout.scale
        if np.issubdtype(part.dtype, np.floating):
            data[~np.isfinite(data)] = 0.0
        return rgb_to_rho_phi_psi(data) if self.colour == "rho-phi-psi" else data

    def _write(self, out, box, solved, omega):
        """Omega's colour channels of the box from the solution (everything else of `out`
        stays the input's, bit for bit)."""
        y0, y1, x0, x1 = box
        colour = rho_phi_psi_to_rgb(solved) if self.colour == "rho-phi-psi" else solved
        values = colour[:, omega] * self.layout.scale + self.layout.offset
        if np.issubdtype(self.layout.dtype, np.integer):
            info = np.iinfo(self.layout.dtype)
            values = np.clip(np.rint(values), info.min, info.max)
        view = out[np.newaxis] if self.layout.channel_axis is None else np.moveaxis(
            out, self.layout.channel_axis, 0)
        view[: self.ncolour, y0:y1, x0:x1][:, omega] = values.astype(self.layout.dtype)

    def _boxes(self):
        from .inpainting import boxes, margin

        ny, nx = self.mask.shape
        if not self.boxes:
            return [(0, ny, 0, nx)]
        align = getattr(self.module, "ALIGN", None)
        return boxes.boxes(
            self.mask, lambda crop: margin(self.module, crop, self.params),
            (lambda crop: align(crop, **self.params)) if callable(align) else lambda crop: 1)

    @deprecated("iterate", "states")
    def states(self, every: int | None = None) -> Iterator[InpaintState]:
        """Deprecated alias of `iterate`."""

    def iterate(self, every: int | None = None) -> Iterator[InpaintState]:
        """Run to the end, yielding an InpaintState at the start of the finest level, every
        `every` steps there (rounded to whole check intervals) and at the end. Coarser
        levels run without yielding. Afterwards `result` and `info` are set."""
        from .inpainting import soft

        start = time.perf_counter()
        out = self.image.copy()
        if not self.mask.any():
            self.result = out
            self.info = InpaintInfo(0, True, 0)
            yield InpaintState(0, 0, self.result)
            return
        runtime = get_runtime(self.device)
        info = InpaintInfo(0, True, 0, method=self.method)
        soft_mask = soft(self.module)
        boxes = self._boxes()
        # Each box's finest level keeps the ping-pong pair, prev and known, the one-channel
        # weight and three index lists on the device: every box is checked before any work.
        for y0, y1, x0, x1 in boxes:
            check_fits(runtime, (self.ncolour, y1 - y0, x1 - x0), "inpainting",
                       4 + 4 / self.ncolour, ghost=GHOST, dtype=self.dtype)
        # A callable progress hears masked pixels done over all to do, once per box; the
        # methods' own step counts would mix units, so inside a box they only repeat the
        # last figure (which is where a caller's cancel gets its chance to raise).
        report = self.progress if callable(self.progress) else None
        done, total = 0, int(sum(self.mask[y0:y1, x0:x1].astype(bool).sum()
                                 for y0, y1, x0, x1 in boxes))
        inner = self.progress if report is None else (lambda *_: report(done, total))
        self._inner_progress = inner
        for box in boxes:
            y0, y1, x0, x1 = box
            omega = np.array(self.mask[y0:y1, x0:x1], bool)
            data = self._box_data(box)
            damage = None if self.softness is None else np.asarray(
                self.softness[y0:y1, x0:x1], np.float64)
            fidelity = None if damage is None else np.where(omega, 1.0 - damage, 0.0)
            method, options, part = self.method, {}, None
            if self.auto:
                from .inpainting import choose

                depth = choose.hole_depth(omega)  # both measures need it
                method, options = choose.pick(choose.features(data, omega, depth), self.method)
                if method == "exemplar" and options.get("structure"):
                    # the thick-hole rule: only the thick components go to the exemplar, in
                    # a second pass after the structure method has filled the whole box
                    # (text and scratches cost the exemplar 10x the time for no gain)
                    part = choose.exemplar_part(omega, depth)
                    if np.array_equal(part, omega):
                        part = None
                    else:
                        method, part = self.method, part if part.any() else None
            info.box_methods.append(method if part is None else f"{method}+exemplar")
            by_exemplar = omega if method == "exemplar" else part
            info.box_exemplar_pixels.append(0 if by_exemplar is None else int(by_exemplar.sum()))
            if method == "exemplar" and method != self.method:
                solved = self._exemplar_box(runtime, box, data, options)
                if damage is not None:
                    solved = np.where(omega, damage * solved + (1 - damage) * data, data)
                info.levels = max(info.levels, 1)
            elif self.method == "transport":
                run = TransportRun(runtime, data, omega, self.p, levels=self.levels,
                                   dtype=self.dtype, progress=inner, fidelity=fidelity)
                for steps, change, solved in run.states(every):
                    self._write(out, box, solved, omega)
                    yield InpaintState(0, info.steps + steps, out.copy(), change)
                solved = run.solution
                info.steps = max(info.steps, run.steps)
                info.converged &= run.converged
                info.levels = max(info.levels, run.levels)
                info.steps_per_level = run.steps_per_level
                info.band_pixels += run.band_pixels
            else:
                extra = {"fidelity": fidelity} if soft_mask and fidelity is not None else {}
                solved = self.module.solve(data, omega, runtime, dtype=self.dtype,
                                           progress=inner, seed=self.seed,
                                           **self.params, **extra)
                solved = np.asarray(solved, np.float64)
                if damage is not None and not soft_mask:
                    solved = np.where(omega, damage * solved + (1 - damage) * data, data)
                info.levels = max(info.levels, 1)
            if part is not None:
                thick = self._exemplar_box(runtime, box, data, options, part=part,
                                           filled=solved)
                if damage is not None:
                    thick = damage * thick + (1 - damage) * data
                solved = np.where(part, thick, solved)
            self._write(out, box, solved, omega)
            info.omega_pixels += int(omega.sum())
            info.boxes.append(box)
            if report is not None:
                done += int(omega.sum())
                report(done, total)
        self.result = out
        self.info = info
        info.seconds = time.perf_counter() - start
        if every:
            yield InpaintState(0, info.steps, self.result)

    def _exemplar_box(self, runtime, box, data, options, part=None, filled=None):
        """The exemplar's fill of a box that auto gave it: solved in the box grown by the
        exemplar's search region (the structure method's box is too small to copy from),
        with every masked pixel there unknown; returns the box's part. With `part` (the
        box's pixels to fill) and `filled` (the box already filled by the structure
        method), the box's other masked pixels count as known, with their filled values."""
        from .inpainting import exemplar

        y0, y1, x0, x1 = box
        ny, nx = self.mask.shape
        m = exemplar.MARGIN()
        big = (max(0, y0 - m), min(ny, y1 + m), max(0, x0 - m), min(nx, x1 + m))
        big_data = self._box_data(big)
        hole = np.array(self.mask[big[0]:big[1], big[2]:big[3]], bool)
        inner = (slice(y0 - big[0], y1 - big[0]), slice(x0 - big[2], x1 - big[2]))
        if part is not None:
            big_data[(slice(None),) + inner] = filled
            hole[inner] = part
        solved = exemplar.solve(big_data, hole, runtime, dtype=self.dtype,
                                progress=self._inner_progress, seed=self.seed, **options)
        solved = np.asarray(solved, np.float64)[(slice(None),) + inner]
        return np.where(self.mask[y0:y1, x0:x1], solved, data)

    def run(self) -> np.ndarray:
        for _ in self.iterate():
            pass
        return self.result


def choose_method(omega: np.ndarray, method: str | None, params=(), per_box=False) -> str:
    """The method to run. None is "auto", unless `params` holds one of the transport's own
    options (InpaintParams), when it is "transport" (the thesis's scheme); "auto" is the
    first installed of inpainting.AUTO (docs/inpainting.md has the measurements), which
    each box may trade for the exemplar (inpainting/choose.py). per_box=True returns
    "auto" itself in that case."""
    from . import inpainting

    if method is None:  # levels too: the transport's multiresolution
        transport_only = {"levels", *InpaintParams.__dataclass_fields__}
        method = "transport" if set(params) & transport_only else "auto"
    if method == "auto" and per_box:
        return method
    if method == "auto":
        installed = inpainting.available()
        return next(name for name in inpainting.AUTO if name in installed)
    inpainting.load(method)  # a clear error for unknown or missing ones
    return method


def inpaint(image: ArrayLike, mask: ArrayLike | None = None, *, channel_axis: int | None = None,
            dt: float = 0.1, transport_steps: int = 15, diffusion_steps: int = 2,
            diffusion_dt: float = 0.1, epsilon: float = 3.0, presmooth: int = 1,
            scaling: str = "none", rotation: str = "ccw", max_steps: int = 3000,
            tol: float = 1e-4, mean_tol: float = 4e-4, check_every: int = 2,
            levels: int | None = None, colour: str = "channels", alpha: bool | None = None,
            fill: str = "biharmonic", keep_band: bool = True, device: DeviceLike = None,
            dtype: DTypeLike | None = None, progress: Progress = None,
            snapshots: int | None = None, return_info: bool = False, method: str | None = None,
            boxes: bool = True, seed: int | None = None, precision: DTypeLike | None = None,
            **options: Any) -> (np.ndarray | tuple[np.ndarray, InpaintInfo]
                                | tuple[np.ndarray, list[InpaintState]]):
    """Fill the masked region of an image.

    image: 2-D greyscale, or 3-D with `channel_axis` (any number of channels); uint8,
        uint16, other integers or floats of any range (scaled to [0, 1] internally).
    mask: (rows, columns) array. bool or integer: nonzero where to inpaint. float: the
        degree of damage in [0, 1], 1 unknown, 0 known; a pixel in between keeps a fidelity
        (1 - m) to its observed value (a soft mask; NaN or values outside [0, 1] are an
        error). None fills the NaN pixels of a float image.
    method: 'auto' (per box of the mask: the exemplar where the surroundings repeat, or
        on the parts of the hole at least 6 px thick in surroundings with detail, else
        coherence transport where installed, else the transport; calibrated on the
        benchmark, docs/inpainting_texture.md; info.box_methods names each box's,
        info.box_exemplar_pixels counts the exemplar's pixels), 'transport'
        (the thesis's scheme, options below), 'coherence', 'navier-stokes', 'exemplar'
        (texture, periodic patterns), 'structure-texture' (clpde.inpainting.available()
        lists what is installed). None, the default, is 'auto', or 'transport' when any
        transport option below is given. Options of methods other than 'transport' go in
        **options.
    boxes: solve each connected component of the mask, or cluster of nearby components,
        in its own box grown by the method's margin (True), so that time and memory follow
        the damage; False solves the whole image at once. Results agree (bit for bit where
        each run takes the same number of steps; each box stops on its own).
    seed: for methods with randomness.

    method="transport" options (thesis chapter 3):
    dt, transport_steps, diffusion_steps: the time step and the A / B schedule (0.1, 15, 2).
    diffusion_dt: time step of the interleaved anisotropic diffusion (<= 0.25; appendix A's
        code uses 0.2, the text 0.1).
    epsilon: width of the band Omega-epsilon around Omega (>= 2 pixels).
    presmooth: steps of anisotropic diffusion of the box before the loop.
    scaling: 'none' uses eq. (3.6) as printed; 'quartic-root' applies sign(I_t) |I_t|^(1/4)
        to the transport update as appendix A's code does, on its 0..255 scale. The root
        keeps faint structures moving but never settles (the largest change stays near
        dt |I_t|^(1/4)), so with it the run usually ends at max_steps.
    rotation: 'ccw' or 'cw' rotation of the gradient (the steady state is the same).
    max_steps, tol, mean_tol, check_every: stop after max_steps steps per level, or once,
        over check_every cycles of A + B steps, the largest change inside Omega is below
        tol or the mean change there is below mean_tol (in [0, 1] units; 0 turns a test
        off), checked on the device. On photos the largest change rarely settles: a few
        dozen pixels next to the border cycle as the limiter's branch flips with the sign
        of beta, and isophotes closed inside Omega keep drifting, while the mean change
        falls steadily; the mean test (4e-4) also stops near the best PSNR on photos, which
        slowly falls afterwards as texture of the border is carried inwards.
    levels: number of resolution levels; None picks it per box from the mask's thickness
        (1 for half-widths up to 8 px, else 2: multiresolution.auto_levels, measured).
    colour: 'channels' inpaints every channel independently; 'rho-phi-psi' inpaints the
        luminance-chroma model of thesis Figure 3.7 (3 colour channels; any method).
    alpha: treat the last channel as alpha, which passes through untouched; None means yes
        for 4-channel images.
    fill: start inside Omega (on the coarsest level): 'biharmonic', 'diffusion' (the
        harmonic fill, iterated on the device), 'mean' or 'zero'. The steady state hardly
        depends on it (thesis 3.3.3), but the best PSNR on photos comes early, so the start
        matters: the biharmonic one is 0.3-0.5 dB better than the harmonic one on the
        benchmark's text and scratch masks and needs fewer steps.
    keep_band: reset the known pixels of Omega-epsilon after each diffusion batch (True), or
        let the diffusion keep smoothing them cycle after cycle (False).
    stencil: 'isotropic' (default) takes grad I in N and delta L (eqs. 3.7, 3.9) with
        Scharr's derivatives; 'central' with appendix A's central differences, whose
        discrete delta L and N are not parallel on sharp isophotes at 30 or 60 degrees, so
        that oblique stripes bleed (docs/inpainting.md: +1.6 to +3.8 dB on stripes at
        30-60 degrees; about 2x the time per step).
    coarse_start: with levels > 1, the start of a finer level: 'corrected' (the upsampled
        coarse result plus the extension of its mismatch with the known border pixels, so
        that no seam is left) or 'upsampled' (the upsampled coarse result as it is).
    A soft mask's fidelity acts after every A + B cycle on the finest level: a pixel of
        damage m is moved (1 - m) of the way back to its observed value.
    snapshots: an integer N: also keep the intermediate states (InpaintState) every N steps
        of the finest level.
    return_info: also return an InpaintInfo (steps taken, whether it converged, ...).
    dtype: the device's arithmetic, float32 (default) or float64 (`precision=` is its
        deprecated old name). device, progress: as for `clpde.diffuse`.

    Returns one of three shapes (a public contract, kept as it is):
    - `image` by default;
    - `(image, info)` with return_info (then info.snapshots holds the states, if asked for);
    - `(image, [InpaintState, ...])` with snapshots and without return_info.
    `image` has the input's shape and dtype, and equals it bit for bit outside the mask.
    `Inpainting` is the object form with the same keywords: `iterate(every)` yields the
    states, and `result` and `info` are set at the end.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> ramp = np.tile(np.linspace(0, 255, 48), (48, 1)).astype(np.uint8)
    >>> mask = np.zeros((48, 48), bool)
    >>> mask[18:30, 18:30] = True
    >>> restored, info = clpde.inpaint(ramp, mask, return_info=True)
    >>> restored.dtype, restored.shape
    (dtype('uint8'), (48, 48))
    >>> bool((restored[~mask] == ramp[~mask]).all())   # untouched outside the mask
    True
    >>> int(np.abs(restored.astype(int) - ramp).max()) <= 2
    True
    >>> len(info.box_methods)                           # one box of damage, one method
    1
    """
    given = locals()  # the transport options are InpaintParams' fields, named alike here
    transport = {name: given[name] for name in _TRANSPORT_ARGS}
    if snapshots is not None and (isinstance(snapshots, bool) or not isinstance(snapshots,
                                                                                (int, np.integer))
                                  or snapshots < 1):
        raise InputError(f"snapshots must be a positive integer (every N steps), not {snapshots!r}")
    # Only the transport options the caller changed are passed on: the defaults are those
    # of InpaintParams, and another method rejects a transport option it lacks by name.
    defaults = inspect.signature(inpaint).parameters
    params = {k: v for k, v in transport.items() if not _same(v, defaults[k].default)}
    params.update(options)
    dtype = renamed_keyword("dtype", dtype, "precision", precision)
    job = Inpainting(image, mask, channel_axis=channel_axis, alpha=alpha, colour=colour,
                     levels=levels, device=device, dtype=dtype, progress=progress,
                     method=method, boxes=boxes, seed=seed, **params)
    states = list(job.iterate(every=snapshots))
    if snapshots:
        job.info.snapshots = states
    if return_info:
        return job.result, job.info
    if snapshots:
        return job.result, states
    return job.result


def _same(value, default) -> bool:
    return type(value) is type(default) and value == default
