"""Navier-Stokes inpainting after Bertalmio, Bertozzi & Sapiro, "Navier-Stokes, fluid
dynamics, and image and video inpainting" (CVPR 2001): the next step the thesis names in
its chapter 5.

The image intensity I is read as the stream function of a 2-D incompressible flow: its
isophotes are streamlines, the velocity is v = grad-perp I and the vorticity is
w = Lap I. Inside the hole the vorticity is transported along the isophotes and diffused
anisotropically,

    w_t + v . grad w = nu div(g(|grad w|) grad w),     g(s) = 1 / (1 + (s / K)^2),

and the image is recovered from Lap I = w in the hole, with the known pixels as boundary
values, by a Poisson solve on the device (conjugate gradients over the hole's index list,
clpde.inpainting.poisson). The two alternate until the image stops changing: at the
steady state, without diffusion, v . grad w = 0, i.e. the smoothness (the Laplacian) is
constant along the isophotes, the same condition as the thesis's transport inpainting.

This is not OpenCV's `cv2.INPAINT_NS`: that is a one-pass fast-marching fill from the
border inwards (each pixel a weighted mean of its known neighbours, the weighting inspired
by the same paper), with no vorticity, no iteration and no steady state.

How it runs (all on the device, in the hole's box): the start is the biharmonic fill; w is
initialised to L I and kept equal to L I of the current image on the known pixels around
the hole (its boundary values); every outer iteration takes `steps` explicit steps of
the vorticity equation (first-order upwind transport, Perona-Malik-type face fluxes for
the diffusion, dt at 0.9 of the stability limit), then warm-started CG iterations of the
Poisson solve; every `check_every` iterations the largest and the mean change of I in the
hole are reduced on the device, and the run stops once the largest is below `tol` or the
mean below `mean_tol` (on photos a few pixels keep moving while the rest has settled).
On holes at least `holdout` (4) px deep the run stops earlier where the same run with a
ring of known pixels hidden too filled that ring clearly better at an earlier check
(holdout.py; the box's margin grows by the ring).

Defaults (nu = 0.05, K = contrast = 0.2) from benchmarks/inpaint_methods_quick.py-style
runs on two photos' scratches, edges at 30/60 degrees and stripes at 30/45 degrees across a
slot: less diffusion (nu = 0.01, K = 0.05) continues edges better but takes several times
the iterations and loses on the photos, where NS stays below its own biharmonic start
either way (docs/inpainting_methods.md has the figures).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from scipy import ndimage

from ..errors import ClpdeError, InputError
from ..imagedata import positive
from . import bounds, holdout
from .poisson import DeviceList, PoissonSolver, box_around, ring_mean_start, thick
from .registry import register

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/navier_stokes.cl",)

MARGIN = 3  # the biharmonic start reads two pixels past the hole; L I on the ring, one more
# The half-thickness (px) of the slot nu's default was chosen on (6 px wide): thicker holes
# get nu * (r / SLOT_HALF)^2 (scaled_nu).
SLOT_HALF = 3.0


def scaled_nu(nu: float, omega: np.ndarray) -> float:
    """The vorticity's diffusion for a box whose hole is r px thick at its deepest (r the
    largest distance to a known pixel): nu for holes up to SLOT_HALF, nu * (r / SLOT_HALF)^2
    beyond. Diffusion reaches sqrt(nu t) in time t, so this keeps the reach across the hole
    per step what it is in the slot: with a fixed nu, the vorticity of a textured border
    (its Laplacian, noise at the pixel scale) is transported deep into a thick hole nearly
    undamped, and the Poisson solve integrates it twice into drifts far below the
    biharmonic start (gravel, 9.7 dB against 14.5). Measured on the calibration half of
    the inpainting corpus (docs/inpainting_methods.md)."""
    r = float(ndimage.distance_transform_edt(omega).max()) if omega.any() else 0.0
    return float(nu) * max(1.0, r / SLOT_HALF) ** 2


@dataclass(frozen=True)
class NavierStokesOptions:
    """method="navier-stokes"'s options (the module docstring), checked on construction.

    Parameters
    ----------
    nu : float
        The vorticity's diffusion (>= 0) in holes up to 6 px thick; a thicker hole's is
        scaled by the square of its half-thickness over 3 px (`scaled_nu`).
    contrast : float
        The edge-stopping diffusion's contrast (> 0).
    steps : int
        Vorticity transport steps between Poisson solves.
    cg_iterations : int
        Conjugate-gradient iterations of each Poisson solve.
    max_iter : int
        Outer iterations at most.
    tol : float
        Stop once the largest change in the hole is below it (0: off).
    mean_tol : float
        Stop once the mean change in the hole is below it (0: off).
    check_every : int
        Outer iterations between the checks.
    holdout : int
        Width (px) of the ring of known pixels hidden in a second run; the run stops at the
        check that filled that ring best, where this comes before the stops above
        (holdout.py). Holes thinner than it keep the stops above; 0 turns it off.
    """

    nu: float = 0.05
    contrast: float = 0.2
    steps: int = 5
    cg_iterations: int = 10
    max_iter: int = 1000
    tol: float = 1e-4
    mean_tol: float = 1e-5
    check_every: int = 10
    holdout: int = holdout.WIDTH

    def __post_init__(self) -> None:
        if not np.isfinite(self.nu) or self.nu < 0:
            raise InputError(f"nu must be a number >= 0, not {self.nu!r}")
        positive("contrast", self.contrast)
        for name in ("tol", "mean_tol"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise InputError(f"{name} must be a number >= 0, not {value!r}")
        for name in ("steps", "max_iter", "cg_iterations", "check_every"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InputError(f"{name} must be an integer >= 1, not {v!r}")
        h = self.holdout
        if isinstance(h, bool) or not isinstance(h, (int, np.integer)) or h < 0:
            raise InputError(f"holdout must be an integer >= 0, not {h!r}")


class NavierStokesSolver:
    """The coupled vorticity transport and Poisson solve on one box; state on the device."""

    def __init__(
        self,
        runtime,
        box: np.ndarray,
        omega: np.ndarray,
        *,
        nu=0.05,
        contrast=0.2,
        dtype=np.float32,
    ):
        self.runtime = runtime
        dt = self.dtype = np.dtype(dtype)
        nc, ny, nx = box.shape
        self.nc, self.ny, self.nx = nc, ny, nx
        q = self.queue = runtime.queue
        start = PoissonSolver(
            runtime, ring_mean_start(box, omega), omega, "biharmonic", dt, precondition=thick(omega)
        )
        start.solve(tol=1e-4, max_iter=5000)
        # the Poisson solver owns the image: its u is I, its f the vorticity in the hole
        self.poisson = PoissonSolver(runtime, start.result(), omega, "harmonic", dt)
        del start
        self.img = self.poisson.u
        self.w = self.poisson.f
        self.wn = cla.zeros(q, box.shape, dt)
        self.prev = self.img.copy()
        self.omega_list = self.poisson.omega_list
        ring = ndimage.binary_dilation(omega, ndimage.generate_binary_structure(2, 1)) & ~omega
        self.ring_list = DeviceList(runtime, np.flatnonzero(ring))
        self.partial = cla.zeros(q, (nc, self.omega_list.items), dt)
        self.partial_sum = cla.zeros(q, (nc, self.omega_list.items), dt)
        k_lap = runtime.kernel("inpainting/navier_stokes.cl", "navier_stokes_laplacian", dt)
        k_step = runtime.kernel("inpainting/navier_stokes.cl", "navier_stokes_vorticity_step", dt)
        k_change = runtime.kernel("inpainting/navier_stokes.cl", "navier_stokes_change", dt)
        dims = (np.int32(nx), np.int32(ny))
        self.dt = 0.9 / (1.0 + 4.0 * nu)
        self._laplacian_ring = self.ring_list.bind(
            runtime, k_lap, nc, self.img.data, self.w.data, *dims
        )
        laplacian_hole = self.omega_list.bind(runtime, k_lap, nc, self.img.data, self.w.data, *dims)
        s = dt.type
        self._steps = [
            self.omega_list.bind(
                runtime,
                k_step,
                nc,
                a.data,
                b.data,
                c.data,
                s(self.dt),
                s(nu),
                s(1.0 / contrast**2),
                *dims,
            )
            for a, b, c in ((self.img, self.w, self.wn), (self.img, self.wn, self.w))
        ]
        self._change = self.omega_list.bind(
            runtime,
            k_change,
            nc,
            self.img.data,
            self.prev.data,
            self.partial.data,
            self.partial_sum.data,
            *dims,
        )
        laplacian_hole()
        # both vorticity buffers hold the boundary values
        self._laplacian_ring()
        cl.enqueue_copy(q, self.wn.data, self.w.data)
        self.iterations = 0
        self.changes, self.mean_changes = [], []

    def iterate(self, steps: int, cg_iterations: int) -> None:
        for k in range(steps):
            self._steps[k % 2]()
        if steps % 2:
            cl.enqueue_copy(self.queue, self.w.data, self.wn.data)
        self.poisson.solve(max_iter=cg_iterations, fixed=True)
        self._laplacian_ring()  # the boundary values follow the image
        cl.enqueue_copy(self.queue, self.wn.data, self.w.data)
        self.iterations += 1

    def change(self) -> tuple[float, float]:
        """Largest and mean |I - I at the last check| in the hole (device partials)."""
        self._change()
        largest = float(self.partial.get().max())
        mean = float(self.partial_sum.get().astype(np.float64).sum()) / max(
            self.omega_list.n * self.nc, 1
        )
        return largest, mean

    def run(
        self,
        *,
        steps=5,
        cg_iterations=10,
        max_iter=1000,
        tol=1e-4,
        mean_tol=1e-5,
        check_every=10,
        watch=None,
    ):
        """Iterate until the largest change of I in the hole over `check_every` iterations
        is below tol, or the mean change below mean_tol (0 turns a test off), or max_iter.
        watch(iterations, image), if given, sees the start and every checked state; the
        run stops where it returns True."""
        self.converged = False
        if watch is not None:
            watch(self.iterations, self.result())
        while self.iterations < max_iter:
            for _ in range(check_every):
                self.iterate(steps, cg_iterations)
            largest, mean = self.change()
            if not np.isfinite(largest):
                raise ClpdeError("the Navier-Stokes inpainting diverged; use a smaller nu")
            self.changes.append(largest)
            self.mean_changes.append(mean)
            if watch is not None and watch(self.iterations, self.result()):
                break
            if largest < tol or mean < mean_tol:
                self.converged = True
                break
        return self

    def result(self) -> np.ndarray:
        return self.img.get()

    def vorticity(self) -> np.ndarray:
        return self.w.get()


def inpaint(
    data,
    omega,
    runtime,
    *,
    nu=NavierStokesOptions.nu,
    contrast=NavierStokesOptions.contrast,
    steps=NavierStokesOptions.steps,
    cg_iterations=NavierStokesOptions.cg_iterations,
    max_iter=NavierStokesOptions.max_iter,
    tol=NavierStokesOptions.tol,
    mean_tol=NavierStokesOptions.mean_tol,
    check_every=NavierStokesOptions.check_every,
    holdout=NavierStokesOptions.holdout,
    dtype=np.float32,
    return_solver=False,
):
    """Navier-Stokes inpainting of (channels, rows, cols) data in [0, 1]."""
    NavierStokesOptions(
        nu, contrast, steps, cg_iterations, max_iter, tol, mean_tol, check_every, holdout
    )
    if not omega.any():
        return (data.copy(), None) if return_solver else data.copy()
    if omega.all():
        raise InputError(
            "the mask covers every pixel, so nothing is known to inpaint from; "
            "mark only the damaged region"
        )
    rows, cols = box_around(omega, MARGIN)
    box_omega = omega[rows, cols]
    nu = scaled_nu(nu, box_omega)
    stops = dict(steps=steps, cg_iterations=cg_iterations, tol=tol, mean_tol=mean_tol)
    stops.update(check_every=check_every)
    cap = _held_out_stop(data, omega, runtime, holdout, nu, contrast, dtype, max_iter, stops)
    solver = NavierStokesSolver(
        runtime,
        data[:, rows, cols].astype(np.float64),
        box_omega,
        nu=nu,
        contrast=contrast,
        dtype=dtype,
    )
    solver.run(max_iter=max_iter if cap is None else min(max_iter, cap), **stops)
    # The recovered image obeys no maximum principle: the vorticity of a textured border,
    # integrated into the hole, leaves the known range far, channel by channel, which shows
    # as saturated false colours. Each cluster's fill is held within its ring's range, and
    # its colours within the hull of the ring's colours (bounds.py).
    solved = bounds.limit(
        solver.result().astype(np.float64), data[:, rows, cols], box_omega, hull=True
    )
    out = np.array(data, copy=True)
    out[:, rows, cols] = np.where(box_omega, solved, out[:, rows, cols])
    return (out, solver) if return_solver else out


def _held_out_stop(data, omega, runtime, width, nu, contrast, dtype, max_iter, stops):
    """Outer iterations at which the same run (the same nu), with a ring of known pixels
    `width` px wide hidden too, filled that ring best; None where that is its own stop or
    the hole is thinner than the ring (holdout.py)."""
    band = holdout.ring(omega, width)
    if band is None:
        return None
    rows, cols = box_around(omega | band, MARGIN)
    box = data[:, rows, cols].astype(np.float64)
    tracker = holdout.Tracker(box, band[rows, cols])
    hidden = np.where(band[rows, cols], 0.0, box)
    probe = NavierStokesSolver(
        runtime, hidden, (omega | band)[rows, cols], nu=nu, contrast=contrast, dtype=dtype
    )

    def watch(iterations, image):
        tracker.add(iterations, image)
        return tracker.risen()

    probe.run(max_iter=max_iter, watch=watch, **stops)
    return tracker.best()


def _margin(omega, options: NavierStokesOptions) -> int:
    """MARGIN, and the hidden ring's width on top where the hole is deep enough for it
    (omega None: any hole)."""
    if omega is None or holdout.ring(np.asarray(omega, bool), options.holdout) is not None:
        return MARGIN + options.holdout
    return MARGIN


@register("navier-stokes", NavierStokesOptions, margin=_margin)
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    nu=NavierStokesOptions.nu,
    contrast=NavierStokesOptions.contrast,
    steps=NavierStokesOptions.steps,
    cg_iterations=NavierStokesOptions.cg_iterations,
    max_iter=NavierStokesOptions.max_iter,
    tol=NavierStokesOptions.tol,
    mean_tol=NavierStokesOptions.mean_tol,
    check_every=NavierStokesOptions.check_every,
    holdout=NavierStokesOptions.holdout,
):
    """Registry entry point: Navier-Stokes inpainting (see the module docstring)."""
    data = np.asarray(data)
    out = inpaint(
        data.astype(np.float64, copy=False),
        np.asarray(omega, bool),
        runtime,
        nu=nu,
        contrast=contrast,
        steps=steps,
        cg_iterations=cg_iterations,
        max_iter=max_iter,
        tol=tol,
        mean_tol=mean_tol,
        check_every=check_every,
        holdout=holdout,
        dtype=dtype,
    )
    return out.astype(data.dtype, copy=False)
