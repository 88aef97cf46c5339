"""method="transport": image inpainting by transport of smoothness along isophotes (thesis
chapter 3, appendix A), an inpainting method like the others of clpde.inpainting.

Inside the region Omega to fill, the image evolves by eqs. (3.5)-(3.11),

    I_t = (delta L . N / |N|) |grad I|_limited,   L = Lap I,   N = grad-perp I,

so that the Laplacian (the "smoothness") is carried along the isophotes arriving at the
border of Omega; every A = 15 such steps, B = 2 steps of anisotropic diffusion (3.4),
I_t = g_eps kappa |grad I|, keep the isophotes from crossing. At the steady state the
Laplacian is constant along isophotes.

How this implementation runs it (all on the OpenCL device):

- clpde.inpaint (api.py) runs it as it runs every method: through the registry, in boxes
  around the damage.
- The data is scaled to [0, 1] (the transport term grows with the square of the intensity).
- The box is first smoothed by a few steps of anisotropic diffusion, so that noise does not
  steer the isophote directions (section 3.3.3).
- Start inside Omega: the biharmonic fill on the coarsest level, which matches the border's
  values and slopes; `fill="diffusion"` is the harmonic fill (the steady state of the heat
  equation in Omega with the known pixels as boundary values, iterated on the device). Each
  finer level starts from the upsampled result of the coarser one plus the extension of its
  mismatch with the known border (no seams). A smooth start that already matches the
  border cuts the number of steps several-fold compared with a constant start, and on
  photos, where the best PSNR comes long before the steady state, the biharmonic start
  scores best (docs/inpainting_methods.md; benchmarks/inpaint_quality.py).
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
- Periodic surrounds (`holdout=4`, `holdout_where="periodic"`, the defaults): in a box
  where a cluster of damage at least 4 px deep sits in a pattern that repeats
  (pick.periodic_clusters), the finest level stops earlier where the same scheme, run with
  a ring of known pixels hidden too, filled that ring clearly better at an earlier step
  (holdout.py): the steady state continues a pattern that repeats within the hole's depth
  with a phase nothing fixes, and falls 2-4 dB below its biharmonic start there. Other
  boxes keep the thesis's stop (`holdout_where="all"` validates them too).
- Multiresolution: one level for thin masks (half-width up to 8 px), two for thicker ones
  (docs/inpainting.md has the measurements).
- The output equals the input bit for bit outside the mask.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from .._progress import progress_bar
from ..errors import ClpdeError
from ..fields import Field, Grid, PingPong, index_list
from ..runtime import enqueue_bare, get_runtime
from . import holdout, poisson
from . import multiresolution as mr
from .registry import register
from .transport_params import GHOST, SCALINGS, STENCILS, TransportOptions

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("common/fields.cl", "inpainting/transport.cl", "planar/planar.cl")

# ---------------------------------------------------------------------------------------
# One resolution level on the device


class LevelSolver:
    """The inpainting loop on one resolution level; the state stays on the device."""

    def __init__(
        self,
        runtime,
        data: np.ndarray,
        omega: np.ndarray,
        params: TransportOptions,
        dtype=np.float32,
        fidelity: np.ndarray | None = None,
        observed=None,
    ):
        self.p = params
        nc, ny, nx = data.shape
        self.grid = g = Grid(runtime, nx, ny, nc, GHOST, np.dtype(dtype))
        self.q = runtime.queue
        self.omega = omega

        dist = ndimage.distance_transform_edt(~omega)  # 0 in Omega
        weight = np.where(
            dist < params.epsilon, 0.5 * (1 + np.cos(np.pi * dist / params.epsilon)), 0
        )
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

        self.k_fill = g.kernel("inpainting/transport.cl", "transport_fill")
        self.k_copy = g.kernel(
            "common/fields.cl", "fields_copy_listed"
        )  # keeps the pair equal off a list
        self.k_change = g.kernel("inpainting/transport.cl", "transport_max_change")
        self.k_sum_change = g.kernel("inpainting/transport.cl", "transport_sum_change")
        self.k_ghosts = g.kernel("inpainting/transport.cl", "transport_ghosts")
        # Soft masks: pixels of Omega with fidelity w > 0 are drawn back towards their
        # observed value by w after every cycle.
        self.fidelity = None
        if fidelity is not None and (fidelity > 0).any():
            self.fidelity_list = index_list(g, fidelity > 0)
            self.fidelity = Field.from_host(
                Grid(runtime, nx, ny, 1, GHOST, g.dtype), fidelity[None]
            )
            self.observed = Field.from_host(g, observed)
            self.k_fidelity = g.kernel("inpainting/transport.cl", "transport_fidelity")
        self.sx = np.int32(g.sx)
        self.rot = g.scalar(1.0 if params.rotation == "ccw" else -1.0)
        self.steps = 0
        self._bind_step_kernels(runtime, params)

    def _bind_step_kernels(self, runtime, params) -> None:
        """Kernel instances with every argument set, one per ping-pong direction: a step is
        then a bare enqueue (pyopencl's per-call argument handling costs as much as a step's
        work on a small region; docs/inpainting_methods.md)."""
        g = self.grid
        defines = {
            "SCALING": SCALINGS.index(params.scaling),
            "STENCIL": STENCILS.index(params.stencil),
        }
        bufs = (self.pair.cur.data.data, self.pair.nxt.data.data)
        self._buf_a = bufs[0]

        def bound(kernel, lst, *args):
            (gsize,), (lsize,), run = runtime.list_launch(max(lst.n, 1))
            kernel.set_args(
                *args, lst.indices.data, np.int32(lst.n), np.int32(g.plane), np.int32(run)
            )
            return kernel, (gsize, g.nc), (lsize, 1), lst.n

        def ghosts(buf):
            if not self.ghosts:
                return None
            kernel = runtime.new_kernel(
                "inpainting/transport.cl", "transport_ghosts", g.dtype, **defines
            )
            n = self.ghost_pairs.shape[0]
            kernel.set_args(buf, self.ghost_pairs.data, np.int32(n), np.int32(g.plane))
            return kernel, *runtime.items(n, g.nc), n

        dt, eps = g.scalar(params.dt), g.scalar(1e-10)
        ddt = g.scalar(params.diffusion_dt)
        self._steps = {}
        for src, dst in (bufs, bufs[::-1]):
            self._steps[("transport", src.int_ptr)] = (
                bound(
                    runtime.new_kernel(
                        "inpainting/transport.cl", "transport_step", g.dtype, **defines
                    ),
                    self.omega_list,
                    src,
                    dst,
                    dt,
                    self.rot,
                    eps,
                    self.sx,
                ),
                ghosts(dst),
            )
            self._steps[("diffusion", src.int_ptr)] = (
                bound(
                    runtime.new_kernel(
                        "inpainting/transport.cl", "transport_diffusion", g.dtype, **defines
                    ),
                    self.band_list,
                    src,
                    dst,
                    self.weight.data.data,
                    ddt,
                    eps,
                    self.sx,
                ),
                ghosts(dst),
            )

    def _enqueue_step(self, name: str) -> None:
        """One bound step from the current buffer into the other, ghosts refreshed, swap."""
        step, ghosts = self._steps[(name, self.pair.cur.data.data.int_ptr)]
        for launch in (step, ghosts):
            if launch is not None and launch[3] > 0:
                enqueue_bare(self.q, *launch[:3], "inpainting/transport.cl")
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
            self.k_ghosts(
                self.q,
                *self.grid.runtime.items(n, self.grid.nc),
                field.data.data,
                self.ghost_pairs.data,
                np.int32(n),
                np.int32(self.grid.plane),
            )

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
        kernel = g.kernel("planar/planar.cl", "planar_curvature_step")
        for _ in range(steps):
            g.launch(
                kernel,
                self.pair.cur.data.data,
                self.pair.nxt.data.data,
                self.pair.cur.data.data,
                g.scalar(self.p.diffusion_dt),
                g.scalar(1e-10),
            )
            self.pair.nxt.fill_ghosts()
            self.pair.swap()
        if steps:
            self.pair.nxt.assign(self.pair.cur)
        self.known.assign(self.pair.cur)

    def harmonic_fill(self, iterations: int) -> None:
        for _ in range(iterations):
            self.grid.launch_list(
                self.k_fill,
                self.omega_list,
                self.pair.cur.data.data,
                self.pair.nxt.data.data,
                self.sx,
            )
            self._finish_step(self.pair.nxt)
        self._sync(self.omega_list)

    def max_change(self) -> float:
        """Largest |cur - prev| in Omega (a device reduction; a few numbers come back)."""
        g, lst = self.grid, self.omega_list
        (gsize,), _, _ = g.runtime.list_launch(lst.n)
        partial = cla.empty(self.q, (g.nc, gsize), g.dtype)
        g.launch_list(
            self.k_change, lst, self.pair.cur.data.data, self.prev.data.data, partial.data
        )
        return float(partial.get().max())

    def mean_change(self) -> float:
        """Mean |cur - prev| over Omega and the channels (device partial sums)."""
        g, lst = self.grid, self.omega_list
        (gsize,), _, _ = g.runtime.list_launch(lst.n)
        partial = cla.empty(self.q, (g.nc, gsize), g.dtype)
        g.launch_list(
            self.k_sum_change, lst, self.pair.cur.data.data, self.prev.data.data, partial.data
        )
        return float(partial.get().astype(np.float64).sum()) / max(lst.n * g.nc, 1)

    def cycle(self) -> None:
        """A transport steps, then B diffusion steps."""
        for _ in range(self.p.transport_steps):
            self.transport_step()
        for _ in range(self.p.diffusion_steps):
            self.diffusion_step()
        if self.p.diffusion_steps:
            if self.p.keep_band:
                self.grid.launch_list(
                    self.k_copy, self.ring_list, self.known.data.data, self.pair.cur.data.data
                )
                self._fill_ghosts(self.pair.cur)
            self._sync(self.band_list)
        self.apply_fidelity()
        self.steps += self.p.transport_steps + self.p.diffusion_steps

    def apply_fidelity(self) -> None:
        if self.fidelity is not None:
            self.grid.launch_list(
                self.k_fidelity,
                self.fidelity_list,
                self.pair.cur.data.data,
                self.pair.nxt.data.data,
                self.observed.data.data,
                self.fidelity.data.data,
            )

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
                self.grid.launch_list(
                    self.k_copy, self.omega_list, self.pair.cur.data.data, self.prev.data.data
                )
        yield self.steps, None

    def result(self) -> np.ndarray:
        return self.pair.cur.to_host().astype(np.float64)


# ---------------------------------------------------------------------------------------
# method="transport" on one box: the levels, coarse to fine


class TransportRun:
    """The thesis's scheme on (nc, ny, nx) data in [0, 1]: the pyramid, the start on the
    coarsest level, one LevelSolver per level. `states(every)` yields (steps, change, data)
    on the finest level; afterwards `solution` and the counters are set."""

    def __init__(
        self,
        runtime,
        data,
        omega,
        options: TransportOptions,
        *,
        dtype=np.float32,
        progress=None,
        fidelity=None,
    ):
        self.p = options
        self.runtime, self.data, self.omega = runtime, data, omega
        self.device = runtime  # get_runtime(self.device) is this runtime
        self.levels = _levels(omega, options)
        self.dtype, self.progress, self.fidelity = dtype, progress, fidelity
        self.solution = None
        self.finest_cap = None
        self.steps = 0
        self.steps_per_level = []
        self.converged = False
        self.band_pixels = 0

    def _finest_cap(self) -> int | None:
        """Steps of the finest level at which the same scheme, run with a ring of known
        pixels hidden too (same levels), filled that ring best; None where that is its own
        stop, the hole is thinner than the ring, or the mask is soft (holdout.py)."""
        band = holdout.ring(self.omega, self.p.holdout) if self.fidelity is None else None
        if band is None:
            return None
        if self.p.holdout_where == "periodic" and not holdout.periodic_surround(
            self.data, self.omega
        ):
            return None
        hidden = self.data.copy()
        hidden[:, band] = 0.0
        options = replace(self.p, holdout=0, levels=self.levels)
        probe = TransportRun(
            self.runtime, hidden, self.omega | band, options, dtype=self.dtype, progress=False
        )
        tracker = holdout.Tracker(self.data, band)
        for steps, _, state in probe.states(every=1):
            tracker.add(steps, state)
            if tracker.risen():
                break
        return tracker.best()

    def states(self, every=None):
        p = self.p
        cap = self._finest_cap()
        self.finest_cap = cap
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
                steps_here = p.max_steps if cap is None or not finest else min(p.max_steps, cap)
                for steps, change in solver.run(steps_here, p.tol, p.mean_tol):
                    bar.update(steps - done)
                    done = steps
                    # a stop at the hidden ring's best step is a stop by choice, not a cut
                    if finest and (solver.converged or cap is not None):
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
            return poisson.fill(
                data, omega, get_runtime(self.device), "biharmonic", dtype=self.dtype
            )
        # "diffusion": begin the Jacobi iterations from the nearest known value, which is
        # already close to the harmonic fill of a thin region.
        _, (iy, ix) = ndimage.distance_transform_edt(omega, return_indices=True)
        return data[:, iy, ix]


# ---------------------------------------------------------------------------------------
# The method's interface (clpde.inpainting.registry)

DESCRIPTION = (
    "transport of smoothness along the isophotes, interleaved with anisotropic "
    "diffusion (thesis ch. 3)"
)
SOFT_MASK = True


def _levels(omega, options: TransportOptions) -> int:
    return options.levels if options.levels is not None else mr.auto_levels(omega)


def _reach(options: TransportOptions) -> int:
    """Pixels outside Omega that one level reads: the band Omega-epsilon plus the diffusion
    stencil, the pre-smoothing's reach, the transport's two-cell stencil and the
    biharmonic start's two cells."""
    return int(np.ceil(options.epsilon)) + 1 + options.presmooth + GHOST + 2


def _align(omega, options: TransportOptions) -> int:
    """Boxes start on multiples of 2**(levels - 1), so that their pyramids coincide with
    the whole image's."""
    return 2 ** (_levels(omega, options) - 1)


def _margin(omega, options: TransportOptions) -> int:
    scale = 2 ** (_levels(omega, options) - 1)
    return _reach(options) * scale + scale


def _states(
    data, omega, runtime, options, *, dtype, progress, seed, fidelity, damage=None
) -> TransportRun:
    """The registry's run of one box (seed unused: the scheme is deterministic; a soft
    mask acts through the fidelity)."""
    return TransportRun(
        runtime, data, omega, options, dtype=dtype, progress=progress, fidelity=fidelity
    )


def run(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    fidelity=None,
    **options,
) -> TransportRun:
    """The scheme's run on one box: `states(every)` yields (steps, change, data) on the
    finest level; afterwards `solution` and the counters are set. `options` are
    TransportOptions' fields."""
    return _states(
        data,
        omega,
        runtime,
        TransportOptions(**options),
        dtype=dtype,
        progress=progress,
        seed=seed,
        fidelity=fidelity,
    )


@register(
    "transport",
    TransportOptions,
    margin=_margin,
    align=_align,
    soft_mask=True,
    ghost=GHOST,
    states=_states,
)
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    fidelity=None,
    **options,
):
    """The scheme's result on one box (registry.py's protocol); `options` are
    TransportOptions' fields."""
    scheme = run(data, omega, runtime, dtype=dtype, progress=progress, fidelity=fidelity, **options)
    for _ in scheme.states():
        pass
    return scheme.solution
