"""Explicit diffusion of 3D volumes (kernels/volumes/volume.cl): heat, Perona-Malik (with
Catte's Gaussian pre-smoothing of the field its diffusivity reads), the TV flow and the
level-set mean curvature flow, with voxel spacing: every difference is a physical gradient,
and the stability limit is 1 / (2 sum 1/h^2) (times eps for TV; curvature's as heat's, as
the planar flow's, since its diffusion across the level sets is at most the Laplacian's).
`clpde.diffuse` sends volumes here.

A volume whose fields do not fit the device runs in slabs along z: each round uploads a slab
with `ghost` planes of the volume on either side, runs as many steps as the ghost planes
absorb (a step reads `reach` planes away, so the slab's cut faces spoil at most `reach`
planes per step), and keeps the slab's own planes; the result is the untiled run's."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from .._progress import progress_bar
from ..errors import DeviceMemoryError, InputError
from ..imagedata import check_steps, compute_dtype, positive
from ..runtime import get_runtime
from .grid import VolumeGrid, check_spacing, to_volume_layout

KERNEL_FILES = ("volumes/volume.cl",)

FLOWS = ("heat", "perona-malik", "tv", "curvature")
PARAMS = {
    "heat": (),
    "perona-malik": ("kappa", "edge", "presmooth"),
    "tv": ("eps",),
    "curvature": ("eps",),
}
FIELDS = 4  # device copies of the volume a flow holds (two states, two for Catte or TV)
# Slabs: planes per slab upload, None to size them by the device's memory (tests force few)
TILE_PLANES = None
TV_EPS = 0.005  # as the planar flow's default (clpde.planar.flows.TV_EPS)
CURVATURE_EPS = 1e-10  # added to |grad u|^2, as the planar curvature flow's default


def stability_limit_volume(flow: str, spacing, eps: float = TV_EPS) -> float:
    """The largest stable explicit time step of a volume flow with this spacing (z, y, x)."""
    limit = 1.0 / (2.0 * float(np.sum(1.0 / check_spacing(spacing) ** 2)))
    return limit * eps if flow == "tv" else limit


def gaussian_weights_1d(sigma: float) -> np.ndarray:
    """One-sided weights w[0..r] of a sampled Gaussian of `sigma` voxels, r = ceil(3 sigma),
    summing to 1 over both sides; [1] for sigma 0."""
    if sigma == 0:
        return np.ones(1)
    radius = int(np.ceil(3 * sigma))
    w = np.exp(-0.5 * (np.arange(radius + 1) / sigma) ** 2)
    return w / (w[0] + 2 * w[1:].sum())


def _check_params(flow: str, params: dict) -> dict:
    if flow not in FLOWS:
        raise InputError(f"unknown flow {flow!r} for a volume; choose one of {', '.join(FLOWS)}")
    extra = sorted(set(params) - set(PARAMS[flow]))
    if extra:
        takes = ", ".join(PARAMS[flow]) or "no parameters"
        raise InputError(f"the {flow} flow takes no parameter {extra[0]!r} (it takes {takes})")
    out = {}
    if flow == "perona-malik":
        out["kappa"] = positive("kappa", params.get("kappa", 0.05))
        out["edge"] = params.get("edge", "exp")
        if out["edge"] not in ("exp", "rational"):
            raise InputError(f"edge must be 'exp' or 'rational', not {out['edge']!r}")
        presmooth = float(params.get("presmooth") or 0.0)
        if not np.isfinite(presmooth) or presmooth < 0:
            raise InputError(f"presmooth must be a number >= 0, not {presmooth!r}")
        out["presmooth"] = presmooth
    if flow == "tv":
        out["eps"] = positive("eps", params.get("eps", TV_EPS))
    if flow == "curvature":
        out["eps"] = positive("eps", params.get("eps", CURVATURE_EPS))
    return out


def diffuse_volume(
    volume,
    flow: str = "heat",
    steps: int = 100,
    dt: float | None = None,
    channel_axis: int | None = None,
    device=None,
    *,
    spacing=None,
    progress: bool | None = None,
    dtype=None,
    **params,
):
    """`steps` explicit steps of a flow on a (Z, Y, X[, C]) volume; returns (result, dt, the
    stability limit). Parameters as `clpde.diffuse`; presmooth (Perona-Malik) is in the
    spacing's units, kappa and eps on [0, 1] data per unit of spacing."""
    p = _check_params(flow, params)
    h = check_spacing(spacing)
    steps = check_steps(steps)
    limit = stability_limit_volume(flow, h, p.get("eps", TV_EPS))
    if dt is None:
        dt = 0.8 * limit
    dt = positive("dt", dt)
    if dt > limit * (1 + 1e-9):
        raise InputError(
            f"dt={dt:g} is above the {flow} flow's stability limit {limit:g} for this spacing; "
            "give a smaller dt or leave it out"
        )
    data, layout = to_volume_layout(volume, channel_axis, spacing)
    runtime, real = get_runtime(device), compute_dtype(None, dtype)
    planes = _planes_that_fit(runtime, data.shape, real)
    with progress_bar(progress, steps, f"clpde diffuse {flow} (volume)", unit="step") as bar:
        if planes >= data.shape[1]:
            grid = VolumeGrid(runtime, data.shape, real, h)
            u = _run(grid, data, flow, steps, dt, p, bar)
        else:
            u = _run_slabs(runtime, real, h, data, flow, steps, dt, p, bar, planes)
    return layout.restore(u), dt, limit


def _planes_that_fit(runtime, shape, real) -> int:
    """How many z planes of a (nc, nz, ny, nx) volume's FIELDS copies the device holds
    (TILE_PLANES when set)."""
    if TILE_PLANES is not None:
        return int(TILE_PLANES)
    nc, nz, ny, nx = shape
    plane = nc * ny * nx * np.dtype(real).itemsize
    return int(min(runtime.global_mem // (FIELDS * plane), runtime.max_alloc // plane))


def _reach(flow: str, p: dict, h) -> int:
    """Planes along z a step reads away: one for the stencils, two for TV (its conductance
    is read at the neighbours), one plus the Gaussian's radius for Catte's pre-smoothing."""
    if flow == "tv":
        return 2
    if flow == "perona-malik":
        return 1 + len(gaussian_weights_1d(p["presmooth"] / h[0])) - 1
    return 1


def _run_slabs(runtime, real, h, data, flow, steps, dt, p, bar, planes) -> np.ndarray:
    """`_run` over slabs along z that fit `planes` planes with their ghosts, in rounds."""
    nz = data.shape[1]
    reach = _reach(flow, p, h)
    per_round = max(1, planes // (4 * reach))  # ghosts take at most half the upload
    ghost = reach * per_round
    own = planes - 2 * ghost
    if own < 1:
        raise DeviceMemoryError(
            f"the 3D {flow} flow needs {2 * ghost + 1} planes of the volume on the device at "
            f"once, but it holds {planes}; crop the volume in y or x"
        )
    u = data
    done = 0
    while done < steps:
        k = min(per_round, steps - done)
        out = np.empty_like(u)
        for z0 in range(0, nz, own):
            z1 = min(nz, z0 + own)
            a, b = max(0, z0 - ghost), min(nz, z1 + ghost)
            grid = VolumeGrid(runtime, (data.shape[0], b - a) + data.shape[2:], real, h)
            slab = _run(grid, u[:, a:b], flow, k, dt, p, None)
            out[:, z0:z1] = slab[:, z0 - a : z1 - a]
        u, done = out, done + k
        bar.update(k)
    return u


def _run(grid: VolumeGrid, data, flow, steps, dt, p, bar) -> np.ndarray:
    """`steps` steps of the flow on `data`, on the device at once; `bar` (or None) hears
    each step."""
    rt, q = grid.runtime, grid.runtime.queue
    cur = cla.to_device(q, data.astype(grid.dtype).reshape(-1))
    nxt = cla.empty_like(cur)
    aux = cla.empty_like(cur) if flow in ("tv", "perona-malik") else None
    dts = grid.scalar(dt)
    if flow == "heat":
        step = rt.kernel("volumes/volume.cl", "volume_heat_step", grid.dtype)
    elif flow == "curvature":
        step = rt.kernel("volumes/volume.cl", "volume_curvature_step", grid.dtype)
    elif flow == "tv":
        cond = rt.kernel("volumes/volume.cl", "volume_tv_conductance", grid.dtype)
        step = rt.kernel("volumes/volume.cl", "volume_tv_step", grid.dtype)
        eps2 = grid.scalar(p["eps"] ** 2)
    else:
        step = rt.kernel("volumes/volume.cl", "volume_pm_step", grid.dtype)
        gauss = rt.kernel("volumes/volume.cl", "volume_gauss_axis", grid.dtype)
        inv_k2 = grid.scalar(1.0 / p["kappa"] ** 2)
        edge = np.int32(0 if p["edge"] == "exp" else 1)
        # per axis x, y, z: presmooth in the spacing's units is presmooth / h voxels
        weights = [
            cla.to_device(q, gaussian_weights_1d(p["presmooth"] / hk).astype(grid.dtype))
            for hk in grid.spacing[::-1]
        ]
        tmp = cla.empty_like(cur) if p["presmooth"] > 0 else None
    for _ in range(steps):
        if flow == "heat":
            grid.launch(step, cur.data, nxt.data, dts, *grid.inverse2)
        elif flow == "curvature":
            grid.launch(step, cur.data, nxt.data, dts, grid.scalar(p["eps"]), *grid.inverse)
        elif flow == "tv":
            grid.launch(cond, cur.data, aux.data, eps2, *grid.inverse)
            grid.launch(step, cur.data, aux.data, nxt.data, dts, *grid.inverse2)
        else:
            smooth = cur
            if tmp is not None:
                src, dst = cur, aux
                for axis, w in enumerate(weights):
                    grid.launch(gauss, src.data, dst.data, w.data, np.int32(w.size - 1),
                                np.int32(axis))  # fmt: skip
                    src, dst = dst, (tmp if dst is aux else aux)
                smooth = src
            grid.launch(step, cur.data, smooth.data, nxt.data, dts, inv_k2, edge,
                        *grid.inverse)  # fmt: skip
        cur, nxt = nxt, cur
        if bar is not None:
            bar.update(1)
    return cur.get().astype(np.float64).reshape(data.shape)
