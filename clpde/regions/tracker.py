"""Region tracking on deforming level-set surfaces (thesis section 2.2), in 3D.

The surface S is the zero level set of Phi; each tracked region R is where an auxiliary
function Phi-hat is negative on S, so its boundary is S and Phi-hat = 0 intersected. Both
evolve on the same grid, in a narrow band around S, with kernels/regions/regions.cl:

    Phi_t     = V |grad Phi|                                  (upwind, slope-limited)
    Phi-hat_t = V (N_Phi . N_Phi-hat) |grad Phi-hat|           (the projected velocity)

and are reinitialised to signed distances once the surface may have moved a cell or two
(every few steps at the CFL limit, rarely for slow flows). V comes from beta, the outward
normal speed of S: a constant, the mean curvature (kappa = k1 + k2, mean curvature flow), the
positive part of the Gaussian curvature (towards the centres of curvature, so folds
flatten), morphing toward a target shape, or a user array, fixed or re-sampled in time
(a callable beta(x, y, z, t): sampled at the middle of every block of `reinit_every` steps).
Rigid translations are given as a velocity vector instead: then Phi-hat moves with the
projection of the full velocity on its normal (for a normal speed that is the thesis'
beta N_Phi . N_Phi-hat; tangential motion of S is only known when the velocity is given).

At saved times the host reads the level sets back: marching cubes of Phi = 0, Phi-hat
sampled at the vertices, triangles straddling Phi-hat = 0 split along its zero (frames.py,
mesh.py). This module holds the tracker on the device; api.py the user's entry point,
`track_region`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike, DTypeLike
from tqdm.auto import tqdm  # (the bars' type)

from ..errors import InputError
from ..fields import IndexList, check_fits, compact
from ..grid3d import Grid3D
from ..runtime import DeviceLike, get_runtime
from .mesh import along_normals
from .region_frame import RegionFrame, make_frame

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("regions/regions.cl",)

SPEEDS = {"constant": 0, "mean-curvature": 1, "gaussian": 2, "morph": 3, "array": 4}
GHOST = 3
# Pseudo-time step of the 3D reinitialisation (stable below 1/sqrt(3)). Six Heun iterations
# of 0.45 (2.7 cells of pseudo-time) correct the band as well as eight of 0.3 did, for less
# work; with less pseudo-time an expanding sphere's outer band lagged and its area drifted
# (docs/regions.md, "The tracker's constants").
REINIT_DT = 0.45
# Extension of the Phi-hat along the surface's normals before each reinitialisation: the
# cells within EXTEND_FROM[0] cells of the surface are kept (they fix Phi-hat on the
# surface, so the regions), those beyond EXTEND_FROM[1] cells take the values carried out
# from them. 6 upwind steps of 0.5 (CFL 0.5 sqrt(3) < 1) carry values 3 cells out, about
# twice the 1.6 cells the surface moves between two reinitialisations at most: the
# reinitialisation band's outer cells were reached by earlier extensions, and the Phi-hat
# stay close to constant along the normals in between (the projected flow keeps them so).
# More steps cost sweeps of the reinitialisation band for little; fewer let the caps drift
# (docs/regions.md). Phi-hat stays constant along the normals, meeting the surface at
# right angles (see mesh.along_normals for why), and cells that enter the band as the
# surface moves get values from the surface, not stale ones.
EXTEND_DT = 0.5
EXTEND_ITERATIONS = 6
EXTEND_FROM = (0.8, 1.5)
# When the surface moved only part of the tracker's reinit_distance since the last
# reinitialisation (a slow flow, or a block cut short at a saved time), that part of the
# iterations, but at least these: 2 Heun iterations (0.9 cells of pseudo-time) and 4
# extension steps (2 cells). A curvature flow on a fine grid moves a small fraction of a
# cell per step, so its reinitialisations shrink to these; the curvature flows and caps of
# the tests moved within rounding of the full ones (docs/regions.md).
MIN_REINIT_ITERATIONS = 2
MIN_EXTEND_ITERATIONS = 4

__all__ = ["SPEEDS", "RegionTracker"]


class RegionTracker:
    """Phi and the Phi-hats on the device, stepped together over a narrow band.

    phi: (nz, ny, nx) signed distance (world units, negative inside); phihat: (L, nz, ny, nx)
    auxiliary functions. speed: one of SPEEDS with `scale` converting it to grid units, or
    velocity (cells per unit time) for rigid translation. band_width: half-width in cells of the
    band that is stepped; reinitialisation covers the band dilated by `reinit_ring` cells.
    Steps go in blocks of `reinit_every`; after a block the level sets are reinitialised
    once the surface may have moved `reinit_every * cfl` cells since the last time (every
    block at the CFL limit; far less often for slow flows: see advance).
    aux_at: for speed="array", a function of time giving aux (nz, ny, nx): a time-dependent
    speed, sampled once per block of `reinit_every` steps, at the block's middle (see advance).
    This class stores the band as index lists over dense padded volumes (storage "lists");
    `region_tracker(..., storage=...)` builds the class that api.STORAGE_CLASSES names.

    Examples
    --------
    >>> import numpy as np
    >>> ax = (np.arange(40) - 19.5) * 0.1
    >>> z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    >>> phi = np.sqrt(x**2 + y**2 + z**2) - 0.6
    >>> tracker = RegionTracker(phi, (0.2 - z)[None], 0.1, speed="constant", scale=-5.0)
    >>> tracker.advance(0.1)                     # the sphere grows at 0.5 per unit time
    >>> phi_now, phihats = tracker.volumes()
    >>> bool(phi_now[20, 20, 14] < phi[20, 20, 14])
    True
    """

    def __init__(
        self,
        phi: np.ndarray,
        phihat: np.ndarray,
        spacing: float,
        *,
        speed: str = "constant",
        scale: float = 0.0,
        aux: np.ndarray | None = None,
        velocity: ArrayLike | None = None,
        band_width: float = 5.0,
        reinit_every: int = 4,
        reinit_iterations: int = 6,
        cfl: float = 0.4,
        reinit_ring: int = 3,
        max_speed: float | None = None,
        aux_at: Callable[[float], np.ndarray] | None = None,
        device: DeviceLike = None,
        dtype: DTypeLike = np.float32,
    ):
        self.h = float(spacing)
        self.vmax = 1e30 if max_speed is None else float(max_speed)  # cells per unit time
        self.runtime = get_runtime(device)
        nz, ny, nx = phi.shape
        self.grid = Grid3D(self.runtime, nx, ny, nz, ghost=GHOST, dtype=np.dtype(dtype))
        self.nc = 1 + len(phihat)
        self.mode = SPEEDS[speed]
        self.scale = float(scale)
        self.velocity = None if velocity is None else np.asarray(velocity, np.float64)
        self.width = float(5.0 if band_width is None else band_width)
        self.reinit_every = int(reinit_every)
        self.reinit_iterations = int(reinit_iterations)
        self.reinit_ring = int(reinit_ring)
        if not 0 <= self.reinit_ring <= GHOST:
            raise InputError(f"reinit_ring must lie in 0..{GHOST} cells, not {reinit_ring!r}")
        self.cfl = float(cfl)
        self.aux_at = aux_at
        if aux_at is not None and (speed != "array" or velocity is not None):
            raise InputError("a time-dependent speed (aux_at) needs speed='array' and no velocity")
        if aux_at is not None and aux is None:
            aux = aux_at(0.0)
        # region functions constant along the surface's normals: the extension before each
        # reinitialisation keeps them so, and would otherwise move an oblique one's zero on
        # the surface once (a cap cut by an oblique plane grew; docs/regions.md)
        phihat = along_normals(phi, self.h, np.asarray(phihat, np.float64))
        cells = np.concatenate([phi[None], phihat]) / self.h
        self._setup(cells, aux if aux is None else aux / (self.h if speed == "morph" else 1.0))
        self.time = 0.0
        self.steps = 0
        self.reinits = 0
        # reinitialise when the surface may have moved this many cells since the last time:
        # reinit_every full steps at the CFL limit (a slower flow, like a curvature flow on a
        # fine grid, moves far less per step and needs it far less often)
        self.reinit_distance = self.reinit_every * self.cfl
        self._moved = 0.0  # bound on the cells the surface moved since the last one
        self._vmax = 0.0  # the speed bound (cells per unit time) of the last stable_dt
        self.rebuild()
        self.reinitialize(4 * self.reinit_iterations)

    def _setup(self, cells: np.ndarray, aux: np.ndarray | None) -> None:
        """The level sets `cells` (channels, nz, ny, nx; grid units) and the auxiliary
        volume (aux, or None) on the device, with the work buffers and the kernels."""
        g, q = self.grid, self.runtime.queue
        # cur, nxt, ls0 and stage of every level set, the speed, aux and two masks
        check_fits(
            self.runtime,
            (self.nc,) + tuple(cells.shape[1:]),
            "region tracking",
            4 + 2.5 / self.nc,
            ghost=GHOST,
            dtype=g.dtype,
        )
        # ghosts continue distances linearly: stencils near the border stay meaningful
        self.cur = g.upload(cells, mode="linear")
        self.nxt = self.cur.copy()
        self.ls0 = self.cur.copy()
        self.stage = self.cur.copy()
        self.speed = cla.zeros(q, g.padded_shape, g.dtype)
        self.aux = g.upload(aux[None]) if aux is not None else self.speed
        self._flag = cla.zeros(q, 1, np.int32)
        self._mask = cla.zeros(q, g.padded_shape, np.uint8)
        self._mask2 = cla.zeros(q, g.padded_shape, np.uint8)
        rt, kw = self.runtime, {"dtype": g.dtype, "SPEED": self.mode}
        self._k = {
            "regions_speed": rt.kernel("regions/regions.cl", "regions_speed", **kw),
            "regions_euler": rt.kernel("regions/regions.cl", "regions_euler", NC=self.nc, **kw),
            "regions_heun": rt.kernel("regions/regions.cl", "regions_heun", NC=self.nc, **kw),
            "regions_advect_step": rt.kernel("regions/regions.cl", "regions_advect_step", **kw),
            "regions_reinit3d_targets": rt.kernel(
                "regions/regions.cl", "regions_reinit3d_targets", **kw
            ),
            "regions_reinit3d_step_pre": rt.kernel(
                "regions/regions.cl", "regions_reinit3d_step_pre", **kw
            ),
            "regions_reinit3d_heun_pre": rt.kernel(
                "regions/regions.cl", "regions_reinit3d_heun_pre", **kw
            ),
            "regions_band_near_border": rt.kernel(
                "regions/regions.cl", "regions_band_near_border", **kw
            ),
            "regions_band_max_abs": rt.kernel("regions/regions.cl", "regions_band_max_abs", **kw),
            "regions_heun_average": rt.kernel("regions/regions.cl", "regions_heun_average", **kw),
            "regions_band_mask": rt.kernel("regions/regions.cl", "regions_band_mask", **kw),
            "regions_dilate_mask": rt.kernel("regions/regions.cl", "regions_dilate_mask", **kw),
            "regions_extend_outer": rt.kernel("regions/regions.cl", "regions_extend_outer", **kw),
            "regions_copy_runs": rt.kernel("regions/regions.cl", "regions_copy_runs", **kw),
        }

    # ---- bands ---------------------------------------------------------------------------
    def rebuild(self) -> None:
        """Bands from the current Phi. The work buffers nxt and ls0 must equal cur outside
        the reinitialisation band: every write lands in it (reinitialize syncs it)."""
        g = self.grid
        self.step_band, self.reinit_band = self._bands()
        # the stepping kernels walk runs of consecutive cells (vectorised loops on CPUs).
        # The step's runs are lengthened to whole vectors (16 cells) where the row allows:
        # the extra cells lie outside the band, where band_cutoff is exactly 0, so their
        # values stay as they are (faster stages, docs/regions.md). The reinitialisation's
        # runs are lengthened the same way: its kernels read the band's mask (_reinit_mask)
        # and keep the values of the cells outside it, which the syncs copy unchanged (the
        # work buffers equal cur there).
        self.step_runs = g.runs(self.step_band, pad=16)
        self.reinit_runs = g.runs(self.reinit_band, pad=16)
        # max |V| of each work-item of regions_euler and regions_heun (see stable_dt)
        (items,), _, _ = self.runtime.list_launch(max(self.step_runs.n, 1))
        self._stats = cla.zeros(self.runtime.queue, 2 * items, g.dtype)
        self._stats_fresh = False
        if self.step_band.n == 0:
            raise InputError(
                "the surface vanished (Phi has no zero level set left on the grid); "
                "track for a shorter time"
            )
        with self.runtime.lock:  # pyopencl's fill kernel is shared by every thread
            self._flag.fill(0)
        g.launch_list(
            self._k["regions_band_near_border"],
            self.reinit_band,
            self._flag.data,
            np.int32(g.nx),
            np.int32(g.ny),
            np.int32(g.nz),
            np.int32(g.ghost),
            np.int32(1),
            *g.strides(),
        )
        if self._flag.get()[0]:
            raise InputError(
                f"the surface came within {self.width + self.reinit_ring + 1:.0f} cells of the "
                f"volume's border at t = {self.time:g}: pad phi (and the other volumes) with "
                f"more cells"
            )

    def _bands(self) -> tuple[IndexList, IndexList]:
        """The step band (interior cells with |Phi| < width cells) and the reinitialisation
        band (the step band dilated by reinit_ring cells, a cube), compacted on the device.
        Each launch writes every interior cell of its mask and the masks' ghost entries stay
        0 from their allocation, so nothing is cleared (clearing a large mask costs a sweep
        of the whole volume)."""
        g, q = self.grid, self.runtime.queue
        dims = (np.int32(g.nx), np.int32(g.ny), np.int32(g.nz), *g.strides(), np.int32(g.ghost))
        launch = self.runtime.items(g.ny, g.nz)
        self._k["regions_band_mask"](
            q, *launch, self.cur.data, self._mask.data, g.scalar(self.width), *dims
        )
        step = compact(self.runtime, self._mask)
        src, dst = self._mask, self._mask2
        for stride in (1, g.sx, g.sxy) if self.reinit_ring else ():
            self._k["regions_dilate_mask"](
                q, *launch, src.data, dst.data, np.int32(stride), np.int32(self.reinit_ring), *dims
            )
            src, dst = dst, src
        self._reinit_mask = src  # the reinitialisation band's mask, read by its kernels
        return step, compact(self.runtime, src)

    def reinitialize(self, iterations: int | None = None, extension: int | None = None) -> None:
        """Every level set back to a signed distance in the reinitialisation band:
        `iterations` Heun iterations (default reinit_iterations) after `extension` steps of
        the Phi-hat's extension along the normals (default EXTEND_ITERATIONS; none when
        iterations is 0)."""
        g = self.grid
        its = self.reinit_iterations if iterations is None else int(iterations)
        ext = EXTEND_ITERATIONS if extension is None else int(extension)
        band, k = self.reinit_runs, self._k
        # the band holds every cell written since the last sync (steps write the step band,
        # inside it), so syncing it keeps the work buffers equal to cur everywhere. The
        # extension's first sweep writes every Phi-hat channel of nxt on the band, so only
        # Phi's is copied; nxt is written anew by the first reinitialisation stage after.
        self._sync(self.nxt, channels=1)
        keep, full = (g.scalar(d) for d in EXTEND_FROM)
        for _ in range(ext if its else 0):
            g.launch_runs(
                k["regions_extend_outer"],
                band,
                self.cur.data,
                self._reinit_mask.data,
                self.nxt.data,
                g.scalar(EXTEND_DT),
                keep,
                full,
                *g.strides(),
                channels=self.nc - 1,
            )
            self.cur, self.nxt = self.nxt, self.cur
        self._sync(self.ls0)
        # the subcell fix's targets depend on ls0 alone: computed once into stage (free
        # here: a step writes it before reading it), they save a third of each sweep
        target = self.stage
        if its:
            g.launch_runs(
                k["regions_reinit3d_targets"],
                band,
                self.ls0.data,
                self._reinit_mask.data,
                target.data,
                *g.strides(),
                channels=self.nc,
            )
        for _ in range(its):
            # Heun steps: forward Euler with the slope-limited norm lets a mode grow (a
            # sphere's interface drifted 0.3 cells in 40 reinitialisations). The second
            # stage averages in place (regions_reinit3d_heun_pre): no third buffer, no averaging
            # sweep. Bit for bit regions_reinit3d_step and regions_reinit3d_heun.
            g.launch_runs(
                k["regions_reinit3d_step_pre"],
                band,
                self.cur.data,
                self.ls0.data,
                target.data,
                self.nxt.data,
                g.scalar(REINIT_DT),
                *g.strides(),
                channels=self.nc,
            )
            g.launch_runs(
                k["regions_reinit3d_heun_pre"],
                band,
                self.cur.data,
                self.nxt.data,
                self.ls0.data,
                target.data,
                g.scalar(REINIT_DT),
                *g.strides(),
                channels=self.nc,
            )
        # the next bands may leave cells of this one: nxt and ls0 must equal cur there (stage
        # is read only where a step has written it first, so it needs no sync)
        self._sync(self.ls0, self.nxt)
        self.rebuild()
        self.reinits += 1
        self._moved = 0.0

    def _sync(self, *buffers, channels=None) -> None:
        """Copy cur into the buffers on the reinitialisation band (every channel, or the
        first `channels`)."""
        for dst in buffers:
            self.grid.launch_runs(
                self._k["regions_copy_runs"],
                self.reinit_runs,
                self.cur.data,
                dst.data,
                channels=self.nc if channels is None else channels,
            )

    # ---- time steps ------------------------------------------------------------------------
    def _compute_speed(self) -> None:
        g = self.grid
        g.launch_runs(
            self._k["regions_speed"],
            self.step_runs,
            self.cur.data,
            self.aux.data,
            self.speed.data,
            g.scalar(self.scale),
            g.scalar(self.vmax),
            *g.strides(),
        )

    def stable_dt(self) -> float:
        """Largest stable step (grid units) for the current speeds: one device read. After
        a step, the speeds its two stages met (no sweep); else computed from Phi."""
        if self.velocity is not None:
            fastest = float(np.abs(self.velocity).sum())
            self._vmax = fastest
            return self.cfl / fastest if fastest > 0 else np.inf
        vmax = self._speed_bound()
        self._vmax = vmax
        dt = self.cfl / vmax if vmax > 0 else np.inf
        # curvature flows are parabolic: explicit steps need dt ~ h^2 / (6 diffusivity)
        if self.mode == 1:
            dt = min(dt, 1.0 / (6.0 * abs(self.scale)))
        elif self.mode == 2 and vmax > 0:
            dt = min(dt, 1.0 / (6.0 * np.sqrt(abs(self.scale) * vmax)))
        return dt

    def _speed_bound(self) -> float:
        """max |V| over the step band (cells per unit time)."""
        if self._stats_fresh:
            return float(self._stats.get().max())
        self._compute_speed()
        return self._band_max(self.speed)

    def _band_max(self, volume) -> float:
        """max |volume| over the step band, reduced per work-item on the device."""
        (gsize,), _, _ = self.runtime.list_launch(self.step_band.n)
        out = cla.zeros(self.runtime.queue, gsize, self.grid.dtype)
        self.grid.launch_list(
            self._k["regions_band_max_abs"], self.step_band, volume.data, out.data
        )
        return float(out.get().max())

    def _cutoff(self):
        """Speeds fade out between these |Phi| (cells): the band's outer 2 cells."""
        return self.grid.scalar(self.width - 2.0), self.grid.scalar(self.width)

    def _advect(self, src, dst, dt) -> None:
        """dst = src + dt L(src) on the step band for a rigid motion (velocity)."""
        g, u = self.grid, self.velocity
        g.launch_runs(
            self._k["regions_advect_step"],
            self.step_runs,
            src.data,
            dst.data,
            g.scalar(dt),
            g.scalar(u[0]),
            g.scalar(u[1]),
            g.scalar(u[2]),
            *self._cutoff(),
            *g.strides(),
            channels=self.nc,
        )

    def _stage(self, name, src, dst, dt) -> None:
        """One Euler stage of every level set over the step band, the speed computed from
        src in the same sweep: regions_euler, or regions_heun (Heun's averaging into dst)."""
        g = self.grid
        g.launch_runs(
            self._k[name],
            self.step_runs,
            src.data,
            self.aux.data,
            dst.data,
            self._stats.data,
            g.scalar(dt),
            g.scalar(1e-12),
            *self._cutoff(),
            g.scalar(self.scale),
            g.scalar(self.vmax),
            *g.strides(),
        )

    def step(self, dt: float) -> None:
        """One Heun (TVD Runge-Kutta 2) step of every level set."""
        g = self.grid
        if self.velocity is None:
            # two fused sweeps: cur -> nxt, then cur <- (cur + nxt + dt L(nxt)) / 2 in place
            self._stage("regions_euler", self.cur, self.nxt, dt)
            self._stage("regions_heun", self.nxt, self.cur, dt)
            self._stats_fresh = True
        else:
            self._advect(self.cur, self.nxt, dt)
            self._advect(self.nxt, self.stage, dt)
            g.launch_runs(
                self._k["regions_heun_average"],
                self.step_runs,
                self.cur.data,
                self.stage.data,
                self.cur.data,
                channels=self.nc,
            )
        self.time += dt
        self.steps += 1

    def advance(self, until: float, bar: tqdm | None = None) -> None:
        """Step to time `until` (the speeds' time unit), reinitialising when needed.

        Steps go in blocks of `reinit_every`. After a block, the level sets are
        reinitialised when the surface may have moved `reinit_distance` cells since the
        last time (the speed bound times the time stepped: reinit_every steps at the CFL
        limit), at `until`, and after every block of a time-dependent speed (aux_at). That
        speed is sampled once per block, at its middle (the midpoint rule: second order in
        the block's length), and held for the block."""
        dt = self.stable_dt()
        while self.time < until - 1e-12:
            self._check_step_count(until, dt)
            steps = [dt] * self.reinit_every
            if self.aux_at is not None:
                steps, dt = self._sample_block(until, dt)
            for dt_k in steps:
                step = min(dt_k, until - self.time)
                if step <= 1e-12:
                    break
                self.step(step)
                self._moved += self._vmax * step
                if bar is not None:
                    bar.update(step)
            done = self.time >= until - 1e-12
            if (
                self.aux_at is not None
                or self._moved >= self.reinit_distance * (1 - 1e-6)
                or (done and self._moved > 0)
            ):
                self._reinitialize_for(self._moved / self.reinit_distance)
            dt = self.stable_dt()

    def _reinitialize_for(self, share: float) -> None:
        """Reinitialise with `share` (<= 1) of the full iterations, at least the minimum:
        the surface moved that share of reinit_distance since the last time."""

        def part(full, least):
            return min(full, max(least, int(np.ceil(full * min(1.0, share) - 1e-6))))

        self.reinitialize(
            part(self.reinit_iterations, MIN_REINIT_ITERATIONS),
            part(EXTEND_ITERATIONS, MIN_EXTEND_ITERATIONS),
        )

    def iterate(
        self,
        times: Iterable[float],
        *,
        origin: ArrayLike = (0.0, 0.0, 0.0),
        keep_volumes: bool = False,
        palette: ArrayLike | None = None,
        partition: bool = False,
        bar: tqdm | None = None,
    ) -> Iterator[RegionFrame]:
        """Advance to each of `times` (ascending) in turn, yielding the RegionFrame there
        (see `make_frame`); `bar` is a tqdm bar counting time."""
        for when in times:
            self.advance(when, bar)
            yield make_frame(self, when, origin, keep_volumes, palette, partition)

    MAX_STEPS = 100_000

    def _check_step_count(self, until, dt) -> None:
        """Refuse a run that would take forever: a speed that a singularity makes huge
        (the curvature at the centre of a sphere a few cells wide, a crease) gives a stable
        step of ~1e-7 and millions of steps (found by fuzzing: it looked like a hang)."""
        needed = (until - self.time) / dt
        if needed > self.MAX_STEPS:
            raise InputError(
                f"the speed's stable time step is {dt:.3g}, so reaching t = {until:g} takes "
                f"{needed:.3g} steps (more than {self.MAX_STEPS}); the curvature of a shape a "
                "few cells wide or of a crease makes the speed huge: pass max_speed= to clamp "
                "|beta|, use a finer grid, or a shorter t"
            )

    def _sample_block(self, until, guess):
        """Upload the time-dependent speed for the next block and return its steps.

        The block's length depends on the speed (its stable step) and the speed on the
        block's middle time, so the length only shrinks until a stable step fits: start
        from `guess` (the stable step at the last sample, infinite for a zero speed), sample
        at the middle, and shorten to reinit_every stable steps of that sample if needed."""
        n = self.reinit_every
        left = until - self.time
        span = min(left, n * guess)
        for _ in range(8):
            self.set_aux(self.aux_at(self.time + 0.5 * span))
            dt = self.stable_dt()
            if n * dt >= span * (1 - 1e-9):
                break
            span = n * dt
        else:  # still shrinking: keep the last sample, with its own stable step
            span = min(span, n * dt)
        return [span / n] * n, dt

    def set_aux(self, values: ArrayLike) -> None:
        """Replace the auxiliary volume (nz, ny, nx) on the device (speed='array': the speed)."""
        g = self.grid
        padded = g.pad(np.asarray(values, np.float64)[None], "edge")
        self.aux.set(np.ascontiguousarray(padded, g.dtype))
        self._stats_fresh = False  # the speeds changed

    def volumes(self) -> tuple[np.ndarray, np.ndarray]:
        """(Phi, Phi-hats) in world units on the host."""
        data = self.grid.download(self.cur).astype(np.float64) * self.h
        return data[0], data[1:]
