"""Harmonic, biharmonic and Poisson fills of a hole, by conjugate gradients on the device.

The unknowns are the hole's pixels (an index list built once); the known pixels around it
are the boundary values. With L the graph Laplacian of the pixel grid (the 5-point stencil,
in Neumann form at the image border):

- harmonic:    L u = 0 in the hole (the steady state of the heat equation);
- biharmonic:  L L u = 0 in the hole, which matches the values and the slopes of the border
  (the 13-point stencil of scikit-image's `inpaint_biharmonic`, solved iteratively here);
- Poisson:     L u = f in the hole, for a given right-hand side f (Navier-Stokes inpainting
  recovers the image from its vorticity this way).

Both systems are symmetric positive definite once the known pixels are moved to the right-
hand side, so plain conjugate gradients converge; every vector operation, the dot products
and the step lengths stay on the device, and the host reads the residuals (a few numbers)
every `check_every` iterations. Colour channels are solved together, one system each.
"""

from __future__ import annotations

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from scipy import ndimage

from ..errors import ClpdeError, InputError

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/poisson.cl",)

KINDS = ("harmonic", "biharmonic")
MARGIN = 2  # the biharmonic stencil reaches two pixels past the hole


def box_around(omega: np.ndarray, margin: int):
    """The (row slice, column slice) of the hole's bounding box grown by margin pixels."""
    rows = np.flatnonzero(omega.any(axis=1))
    cols = np.flatnonzero(omega.any(axis=0))
    ny, nx = omega.shape
    return (
        slice(max(rows[0] - margin, 0), min(rows[-1] + margin + 1, ny)),
        slice(max(cols[0] - margin, 0), min(cols[-1] + margin + 1, nx)),
    )


def item_geometry(runtime, n: int):
    """(global size, local size, chunk, stride, per, items) for poisson.cl's ITEM_ARGS."""
    n = max(int(n), 1)
    if runtime.is_cpu:
        items = max(1, min(8 * runtime.device.max_compute_units, -(-n // 256)))
        per = -(-n // items)
        items = -(-n // per)
        return items, 1, per, 1, per, items  # a fixed work-group: one PoCL build (Runtime.items)
    items = min(1024, -(-n // 64) * 64)
    return items, 64, 1, items, -(-n // items), items


class DeviceList:
    """A host list of flat indices on the device, with its launch geometry."""

    def __init__(self, runtime, flat: np.ndarray):
        self.n = int(flat.size)
        self.buf = cla.to_device(
            runtime.queue,
            np.ascontiguousarray(flat, np.int32) if flat.size else np.zeros(1, np.int32),
        )
        self.gsize, self.lsize, self.chunk, self.stride, self.per, self.items = item_geometry(
            runtime, self.n
        )

    def args(self):
        return (
            self.buf.data,
            np.int32(self.n),
            np.int32(self.chunk),
            np.int32(self.stride),
            np.int32(self.per),
            np.int32(self.items),
        )

    def bind(self, runtime, template: cl.Kernel, nc, *args):
        """A copy of a kernel with its arguments set once: launching it costs no argument
        setting (pyopencl's per-call argument handling dominates a small launch on PoCL),
        and the shared kernel object of the runtime's cache keeps its own arguments."""
        kernel = cl.Kernel(template.program, template.function_name)
        kernel.set_args(*args, *self.args())
        local = (self.lsize, 1)
        queue = runtime.queue
        if self.n == 0:
            return lambda: None
        return lambda: cl.enqueue_nd_range_kernel(queue, kernel, (self.gsize, nc), local)


class Multigrid:
    """A symmetric V-cycle z = M r for the hole's operator, as a CG preconditioner.

    Level l+1 halves level l's box, with a ring of cells outside the hole all around (coarse
    cell (Y, X) covers fine cells 2Y-2, 2Y-1 and 2X-2, 2X-1); its hole is every coarse cell
    with a hole pixel among its four. Vectors are zero off each level's hole (zero
    Dirichlet values for the corrections). Transfer: piecewise-constant interpolation and
    its transpose (the sum of the four children); coarse operators s^l op with op = L or
    L L of the coarse grid, s = 2 from the Galerkin product of those transfers for L
    (R L P = 2 L_c), s = 1.5 for L L (measured: 1 suits thick holes, 2 thin ones); damped
    Jacobi smoothing, two sweeps before and after, eight on the coarsest level. Every launch
    is bound once, so a V-cycle is a fixed sequence of launches with no host work.
    """

    OMEGA = {"harmonic": 0.8, "biharmonic": 0.6}  # Jacobi damping, below 2 / lambda_max
    DIAG = {"harmonic": 4.0, "biharmonic": 20.0}
    COARSE_SCALE = {"harmonic": 2.0, "biharmonic": 1.5}

    def __init__(self, runtime, omega, kind, nc, dtype, level0):
        """level0: (list, b, z, tmp, res): the finest level's list and device buffers (the
        input r, the output z, scratch)."""
        q = runtime.queue
        s = dtype.type
        bi = np.int32(kind == "biharmonic")
        sign = -1.0 if kind == "harmonic" else 1.0
        k_smooth = runtime.kernel("inpainting/poisson.cl", "poisson_mg_smooth", dtype)
        k_scale = runtime.kernel("inpainting/poisson.cl", "poisson_mg_scale", dtype)
        k_residual = runtime.kernel("inpainting/poisson.cl", "poisson_mg_residual", dtype)
        k_restrict = runtime.kernel("inpainting/poisson.cl", "poisson_mg_restrict", dtype)
        k_prolong = runtime.kernel("inpainting/poisson.cl", "poisson_mg_prolong", dtype)
        levels = [(omega.shape, *level0)]
        om = omega
        self.buffers = []  # bound kernels hold no references: keep the buffers alive
        while len(levels) < 9:
            ny, nx = om.shape
            cy, cx = (ny + 1) // 2 + 2, (nx + 1) // 2 + 2
            padded = np.zeros((2 * cy, 2 * cx), bool)
            padded[2 : 2 + ny, 2 : 2 + nx] = om
            coarse = padded.reshape(cy, 2, cx, 2).any(axis=(1, 3))
            if coarse.sum() < 4 or coarse.sum() >= om.sum():
                break
            bufs = [cla.zeros(q, (nc, cy, cx), dtype) for _ in range(4)]
            self.buffers += bufs
            lst = DeviceList(runtime, np.flatnonzero(coarse))
            self.buffers.append(lst)
            b, x, y, r = bufs
            levels.append(((cy, cx), lst, b, x, y, r))
            om = coarse
        self.levels = len(levels)
        self.launches = []
        self.runtime, self.nc = runtime, nc
        out = self._cycle(
            levels, 0, kind, sign, bi, s, k_smooth, k_scale, k_residual, k_restrict, k_prolong
        )
        z, tmp = level0[2], level0[3]
        if out is tmp:  # the result must end in z
            self.launches.append(lambda: cl.enqueue_copy(q, z.data, tmp.data))

    def _cycle(
        self, levels, depth, kind, sign, bi, s, k_smooth, k_scale, k_residual, k_restrict, k_prolong
    ):
        (ny, nx), lst, b, x, y, r = levels[depth]
        launch = self.launches.append
        scale = sign * self.COARSE_SCALE[kind] ** depth
        w = self.OMEGA[kind] / (abs(scale) * self.DIAG[kind])
        dims = (np.int32(nx), np.int32(ny))
        rt, nc = self.runtime, self.nc
        last = depth == len(levels) - 1
        sweeps = 8 if last else 2

        def smooth(count, cur, other):
            for _ in range(count):
                launch(
                    lst.bind(
                        rt, k_smooth, nc, cur.data, other.data, b.data, s(scale), s(w), bi, *dims
                    )
                )
                cur, other = other, cur
            return cur, other

        launch(lst.bind(rt, k_scale, nc, b.data, x.data, s(w), *dims))
        cur, other = smooth(sweeps - 1, x, y)
        if last:
            return cur
        launch(lst.bind(rt, k_residual, nc, cur.data, b.data, r.data, s(scale), bi, *dims))
        (cy, cx), clst, cb = levels[depth + 1][:3]
        launch(clst.bind(rt, k_restrict, nc, r.data, cb.data, *dims, np.int32(cx), np.int32(cy)))
        coarse = self._cycle(
            levels,
            depth + 1,
            kind,
            sign,
            bi,
            s,
            k_smooth,
            k_scale,
            k_residual,
            k_restrict,
            k_prolong,
        )
        launch(
            lst.bind(rt, k_prolong, nc, cur.data, coarse.data, np.int32(cx), np.int32(cy), *dims)
        )
        cur, other = smooth(sweeps, cur, other)
        return cur

    def apply(self):
        for launch in self.launches:
            launch()


class PoissonSolver:
    """CG for L u = f (harmonic) or L L u = f (biharmonic) in a hole of a box.

    `u` is the device field (nc, ny, nx): known values off the hole, the current guess in
    it; solve() improves it in place. `f` (device, same shape) is the right-hand side,
    zero unless set. Other modules (Navier-Stokes) share `u` and set `f` between solves.
    """

    def __init__(
        self,
        runtime,
        values: np.ndarray,
        omega: np.ndarray,
        kind="harmonic",
        dtype=np.float32,
        precondition=False,
    ):
        if kind not in KINDS:
            raise InputError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        self.runtime, self.kind = runtime, kind
        self.dtype = dt = np.dtype(dtype)
        self.nc, self.ny, self.nx = nc, ny, nx = values.shape
        q = self.queue = runtime.queue
        runtime.check_alloc(values.size * dt.itemsize)
        self.u = cla.to_device(q, np.ascontiguousarray(values, dt))

        def zeros(shape=values.shape):
            return cla.zeros(q, shape, dt)

        self.f, self.r, self.p, self.qv = zeros(), zeros(), zeros(), zeros()
        o = self.omega_list = DeviceList(runtime, np.flatnonzero(omega))
        self.rr = [zeros((nc, o.items)), zeros((nc, o.items))]
        self.pq = zeros((nc, o.items))
        self._k_update = runtime.kernel("inpainting/poisson.cl", "poisson_cg_update", dt)
        self._k_direction = runtime.kernel("inpainting/poisson.cl", "poisson_cg_direction", dt)
        self._bind_cg()
        self.mg = None
        if precondition and o.n:
            self._bind_pcg(omega)
        self.iterations = 0
        self.residual = None

    def _bind(self, kernel, *buffers):
        """A launch of `kernel` over the hole's list, its arguments bound once."""
        dims = (np.int32(self.nx), np.int32(self.ny))
        return self.omega_list.bind(
            self.runtime, kernel, self.nc, *(b.data for b in buffers), *dims
        )

    def _apply_launch(self, src, dst, a, b, dot, partial):
        """dst = a L^order src + b f, and the partials of dot . dst (order 1 harmonic, 2
        biharmonic)."""
        s, order = self.dtype.type, 1 if self.kind == "harmonic" else 2
        k_op = self.runtime.kernel("inpainting/poisson.cl", "poisson_operator_axpy_dot", self.dtype)
        return self.omega_list.bind(
            self.runtime,
            k_op,
            self.nc,
            src.data,
            dst.data,
            self.f.data,
            s(a),
            s(b),
            dot.data,
            partial.data,
            np.int32(order),
            np.int32(self.nx),
            np.int32(self.ny),
        )

    @property
    def _sign(self) -> int:
        # harmonic: A = -L, r = b - A u = L u - f; biharmonic: A = L L, r = f - L L u
        return 1 if self.kind == "harmonic" else -1

    def _bind_cg(self) -> None:
        """The plain conjugate gradients' launches, one per parity of the ping-ponged
        residual norms rr."""
        sign, rr = self._sign, self.rr
        self._residual = [self._apply_launch(self.u, self.r, sign, -sign, self.r, rr[0])]
        self._apply = [self._apply_launch(self.p, self.qv, -sign, 0, self.p, self.pq)]
        self._update = [
            self._bind(self._k_update, self.u, self.r, self.p, self.qv, rr[a], self.pq, rr[1 - a])
            for a in (0, 1)
        ]
        self._direction = [
            self._bind(self._k_direction, self.p, self.r, rr[a], rr[1 - a]) for a in (0, 1)
        ]

    def _bind_pcg(self, omega: np.ndarray) -> None:
        """The multigrid preconditioner and the preconditioned recurrences' launches, which
        carry r.z (rz) where plain CG carries r.r."""
        nc, ng, dt, q = self.nc, self.omega_list.items, self.dtype, self.queue
        self.z, tmp, res = (cla.zeros(q, self.u.shape, dt) for _ in range(3))
        self._mg_buffers = (tmp, res)
        self.mg = Multigrid(
            self.runtime, omega, self.kind, nc, dt, (self.omega_list, self.r, self.z, tmp, res)
        )
        rz = self.rz = [cla.zeros(q, (nc, ng), dt), cla.zeros(q, (nc, ng), dt)]
        self.rr_now = cla.zeros(q, (nc, ng), dt)
        k_dot = self.runtime.kernel("inpainting/poisson.cl", "poisson_dot_partial", dt)
        sign = self._sign
        self._pcg_residual = [self._apply_launch(self.u, self.r, sign, -sign, self.r, self.rr_now)]
        self._pcg_update = [
            self._bind(self._k_update, self.u, self.r, self.p, self.qv, rz[a], self.pq, self.rr_now)
            for a in (0, 1)
        ]
        self._pcg_dot = [self._bind(k_dot, self.r, self.z, rz[a]) for a in (0, 1)]
        self._pcg_direction = [
            self._bind(self._k_direction, self.p, self.z, rz[a], rz[1 - a]) for a in (0, 1)
        ]

    def _solve_pcg(self, tol, max_iter, check_every, atol):
        """Conjugate gradients preconditioned by the multigrid V-cycle: the same
        recurrences with z = M r in place of r (alpha = r.z / p.Ap, beta = new r.z / old);
        the residual norm r.r is still what the stopping test reads."""
        for launch in self._pcg_residual:
            launch()
        rr0 = self.rr_now.get().astype(np.float64).sum(axis=1)
        if np.all(rr0 <= atol * atol) or np.all(rr0 == 0):
            self.residual = np.zeros_like(rr0)
            return 0
        self.mg.apply()
        self._pcg_dot[0]()
        cl.enqueue_copy(self.queue, self.p.data, self.z.data)
        it, cur = 0, 0
        while it < max_iter:
            for _ in range(min(check_every, max_iter - it)):
                for launch in self._apply:
                    launch()
                self._pcg_update[cur]()
                self.mg.apply()
                self._pcg_dot[1 - cur]()
                self._pcg_direction[cur]()
                cur = 1 - cur
                it += 1
            rr = self.rr_now.get().astype(np.float64).sum(axis=1)
            if not np.isfinite(rr).all():
                raise ClpdeError(
                    "the conjugate-gradient solve diverged (a non-finite residual); "
                    "use dtype=np.float64"
                )
            if np.all((rr <= tol * tol * rr0) | (rr <= atol * atol)):
                break
        self.iterations += it
        self.residual = np.sqrt(rr / np.maximum(rr0, 1e-300))
        return it

    def _rr(self, which) -> np.ndarray:
        return self.rr[which].get().astype(np.float64).sum(axis=1)

    def solve(self, tol=1e-5, max_iter=5000, check_every=10, atol=0.0, fixed=False):
        """Iterate until every channel's residual norm is below tol times its starting
        norm (or atol), or max_iter; with fixed=True, exactly max_iter iterations and no
        read-back. Returns the number of iterations."""
        if self.omega_list.n == 0:
            return 0
        if self.mg is not None and not fixed:
            return self._solve_pcg(tol, max_iter, check_every, atol)
        for launch in self._residual:
            launch()
        cl.enqueue_copy(self.queue, self.p.data, self.r.data)
        if fixed:
            # a fixed number of iterations with no host read at all (warm-started inner
            # solves of a time loop)
            for it in range(max_iter):
                for launch in self._apply:
                    launch()
                self._update[it % 2]()
                self._direction[it % 2]()
            if max_iter % 2:
                cl.enqueue_copy(self.queue, self.rr[0].data, self.rr[1].data)
            self.iterations += max_iter
            return max_iter
        rr0 = self._rr(0)
        if np.all(rr0 <= atol * atol) or np.all(rr0 == 0):
            self.residual = np.zeros_like(rr0)
            return 0
        it, cur = 0, 0
        while it < max_iter:
            for _ in range(min(check_every, max_iter - it)):
                for launch in self._apply:
                    launch()
                self._update[cur]()
                self._direction[cur]()
                cur = 1 - cur
                it += 1
            rr = self._rr(cur)
            if not np.isfinite(rr).all():
                raise ClpdeError(
                    "the conjugate-gradient solve diverged (a non-finite residual); "
                    "use dtype=np.float64"
                )
            if np.all((rr <= tol * tol * rr0) | (rr <= atol * atol)):
                break
        # the next solve starts from rr[0]
        if cur == 1:
            cl.enqueue_copy(self.queue, self.rr[0].data, self.rr[1].data)
        self.iterations += it
        self.residual = np.sqrt(rr / np.maximum(rr0, 1e-300))
        return it

    def result(self) -> np.ndarray:
        return self.u.get()


def ring_mean_start(data: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """A cheap first guess: each hole component gets the mean of the known pixels around it."""
    grown = ndimage.binary_dilation(omega, np.ones((3, 3), bool))
    labels, n = ndimage.label(grown)
    ring = grown & ~omega
    ring_labels = labels[ring]
    counts = np.maximum(np.bincount(ring_labels, minlength=n + 1), 1)
    hole_labels = labels[omega]
    out = data.copy()
    for c in range(data.shape[0]):
        means = np.bincount(ring_labels, weights=data[c][ring], minlength=n + 1) / counts
        out[c][omega] = means[hole_labels]
    return out


THICK = 16  # half-width (pixels) from which the multigrid preconditioner pays on PoCL


def thick(omega: np.ndarray, half_width: int = THICK) -> bool:
    """Whether some hole pixel lies more than about half_width pixels from the known ones."""
    return bool(
        ndimage.minimum_filter(omega.view(np.uint8), size=2 * half_width + 1, mode="constant").any()
    )


def fill(
    data: np.ndarray,
    omega: np.ndarray,
    runtime,
    kind="biharmonic",
    *,
    dtype=np.float32,
    tol=1e-5,
    max_iter=20000,
    start=None,
    clip=True,
    precondition="auto",
) -> np.ndarray:
    """The harmonic or biharmonic fill of omega, solved in the hole's box on the device.

    data: (channels, rows, cols) floats; only omega changes. start: optional first guess
    inside omega (same shape as data); by default each component's mean border value.
    (A coarse-grid solution as the start hardly cuts the iterations:
    docs/inpainting_methods.md.) clip: clip the result to each
    channel's range over the known pixels, as scikit-image's inpaint_biharmonic does (the
    biharmonic fill overshoots next to sharp edges). precondition: conjugate gradients
    preconditioned by a multigrid V-cycle (`Multigrid`), True, False or "auto": where some
    hole pixel lies more than THICK pixels from the known ones. On PoCL a V-cycle costs
    several plain iterations in launches, so it pays only on thick holes, where it cuts the
    iterations many-fold; on text it cuts them too, but takes more time
    (docs/inpainting_methods.md has the figures).
    """
    if not omega.any():
        return data.copy()
    if omega.all():
        raise InputError(
            "the mask covers every pixel, so nothing is known to fill from; "
            "mark only the damaged region"
        )
    rows, cols = box_around(omega, MARGIN)
    box_omega = omega[rows, cols]
    box = data[:, rows, cols].astype(np.float64)
    if start is None:
        guess = ring_mean_start(box, box_omega)
    else:
        guess = np.asarray(start, np.float64)[:, rows, cols]
    box[:, box_omega] = guess[:, box_omega]
    if precondition == "auto":
        precondition = thick(box_omega)
    solver = PoissonSolver(runtime, box, box_omega, kind, dtype, precondition=bool(precondition))
    solver.solve(tol=tol, max_iter=max_iter)
    solved = solver.result().astype(np.float64)
    if clip:
        known = ~omega
        for c in range(data.shape[0]):  # (per channel: numpy's axis-1 reduction is slower)
            plane = data[c][known]
            np.clip(solved[c], plane.min(), plane.max(), out=solved[c])
    out = np.array(data, copy=True)
    out[:, rows, cols] = np.where(box_omega, solved, out[:, rows, cols])
    return out


def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    kind="biharmonic",
    tol=1e-5,
    max_iter=20000,
):
    """Registry entry point: the harmonic or biharmonic fill (see `fill`)."""
    data = np.asarray(data)
    return fill(
        data, np.asarray(omega, bool), runtime, kind, dtype=dtype, tol=tol, max_iter=max_iter
    ).astype(data.dtype, copy=False)
