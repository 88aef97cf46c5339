"""Images larger than a device: the fixed-step flows run tile by tile through dask.array.

An explicit step of a planar flow reads a cell's 3x3 neighbourhood (stencil radius 1), so
after n steps a cell depends only on the cells within n of it. Each tile is therefore run
with a margin of depth = steps x radius borrowed from its neighbours
(``dask.array.map_overlap``, boundary "none": the image's own borders keep the flow's
Neumann condition), and the margin is cut off again. The result is bitwise identical to
the untiled run: every kept cell sees exactly the values it would see in the whole image,
and the kernels compute each cell with the same arithmetic.

Float images are scaled to [0, 1] once, by the whole image's range (as the untiled flows
do), not per tile. denoise_tv tiles only with a fixed iteration count and a fixed weight:
its stopping test and sigma's lambda update are sums over the whole image.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..fields import Field, Grid, PingPong
from ..imagedata import (
    check_steps,
    compute_dtype,
    positive,
    to_kernel_layout,
)
from ..runtime import get_runtime
from .flows import FLOWS, PlanarFlow, gaussian_weights
from .rof_solvers import primal_dual

RADIUS = 1  # every planar.cl and rof.cl step reads the 3x3 neighbourhood only
# Tiled denoise_tv runs exactly `steps` iterations; a tolerance no change falls below.
_NEVER = 1e-300


class _ScaledFlow(PlanarFlow):
    """A PlanarFlow on data already in the kernels' layout and [0, 1] scale."""

    def __init__(self, data, flow, dt, device, precision, params):

        self.runtime = get_runtime(device)
        nc, ny, nx = data.shape
        self.grid = Grid(self.runtime, nx, ny, nc, 1, np.dtype(precision or np.float32))
        self.flow, self.steps_done, self.time = flow, 0, 0.0
        self.pair = PingPong(Field.from_host(self.grid, data))
        self._setup(
            flow,
            dt,
            params.get("kappa", 0.05),
            params.get("edge", "exp"),
            params.get("eps"),
            None,
            params.get("presmooth"),
        )


def _tile_diffuse(block, flow, steps, dt, device, precision, params):
    state = _ScaledFlow(block, flow, dt, device, precision, params)
    return state.run(steps, progress=False).pair.cur.to_host().astype(np.float64)


def _tile_denoise(block, lam, steps, check_every, device, precision, vectorial=False):

    runtime = get_runtime(device)
    nc, ny, nx = block.shape
    grid = Grid(runtime, nx, ny, nc, 1, compute_dtype(block.dtype, precision))
    u, *_ = primal_dual(
        grid, block, np.full(nc, lam), None, steps, _NEVER, check_every, False, vectorial
    )
    return u


def _chunked(data: np.ndarray, chunks, depth: int, func, **kwargs) -> np.ndarray:
    import dask
    import dask.array as da

    if isinstance(chunks, (int, np.integer)):
        chunks = (int(chunks), int(chunks))
    ny, nx = data.shape[1:]
    cy, cx = (max(1, min(int(c), n)) for c, n in zip(chunks, (ny, nx), strict=False))
    array = da.from_array(data, chunks=(data.shape[0], cy, cx))
    # map_overlap needs each chunk at least as large as the depth; it rechunks if not,
    # which changes only the tiling, never the result.
    out = array.map_overlap(
        func,
        depth={0: 0, 1: depth, 2: depth},
        boundary="none",
        dtype=np.float64,
        meta=np.empty((0, 0, 0)),
        **kwargs,
    )
    # One device per process: the tiles run one after another here, each on the device.
    with dask.config.set(scheduler="synchronous"):
        return out.compute()


def diffuse(
    image,
    flow: str = "heat",
    steps: int = 100,
    dt=None,
    channel_axis=None,
    device=None,
    *,
    chunks=256,
    dtype=None,
    **params,
) -> np.ndarray:
    """clpde.diffuse run tile by tile: the same result, bit for bit, in chunks x chunks tiles
    (each with a margin of `steps` cells), for images larger than the device allows.
    The curvature flow's per-pixel ``weight`` is not supported here."""
    if flow not in FLOWS:
        raise InputError(f"unknown flow {flow!r}; choose one of {', '.join(FLOWS)}")
    if "weight" in params:
        raise InputError("tiled diffuse does not take a weight; run it untiled")
    steps = check_steps(steps)
    data, layout = to_kernel_layout(image, channel_axis)
    runtime = get_runtime(device)
    # Catte's Gaussian reads `radius` more cells on each side before every step
    radius = RADIUS
    if params.get("presmooth") is not None:
        radius += len(gaussian_weights(float(params["presmooth"]))) - 1
    out = _chunked(
        data,
        chunks,
        steps * radius,
        _tile_diffuse,
        flow=flow,
        steps=steps,
        dt=dt,
        device=runtime.index,
        precision=dtype,
        params=params,
    )
    return layout.restore(out)


def denoise_tv(
    image,
    weight,
    steps: int,
    channel_axis=None,
    *,
    device=None,
    chunks=256,
    check_every: int = 5,
    dtype=None,
    precision=None,
    vectorial: bool | None = None,
) -> np.ndarray:
    """clpde.denoise_tv (primal-dual, given weight) for exactly `steps` iterations, tile by
    tile; bitwise equal to ``clpde.denoise_tv(image, weight=weight, max_steps=steps,
    tol=1e-300, check_every=check_every, vectorial=vectorial)`` (vectorial by default for
    several channels, as there: its coupling is per cell, so the reach is the same)."""

    steps = check_steps(steps)
    data, layout = to_kernel_layout(image, channel_axis)
    weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
    lam = weight_unit / positive("weight", weight)
    runtime = get_runtime(device)
    # u = f + div(p)/lambda adds one more cell to the iterations' reach.
    vectorial = data.shape[0] > 1 if vectorial is None else bool(vectorial)
    out = _chunked(
        data,
        chunks,
        steps * RADIUS + 1,
        _tile_denoise,
        lam=lam,
        steps=steps,
        vectorial=vectorial,
        check_every=max(1, int(check_every)),
        device=runtime.index,
        precision=dtype,
    )
    return layout.restore(out)


def exceeds_device(shape, channels: int, device=None, dtype=np.float32) -> bool:
    """Whether one padded field of an image this size is more than the device's largest
    allocation (the dual field of denoise_tv is twice that; checked by the caller)."""
    ny, nx = shape[:2]
    nbytes = channels * (ny + 2) * (nx + 2) * np.dtype(dtype).itemsize
    return nbytes > get_runtime(device).device.max_mem_alloc_size


def may_exceed_device(path, device=None) -> bool:
    """From the file's header only: whether the image at `path` could need tiling (True
    when the header cannot tell)."""
    from pathlib import Path

    try:
        if Path(path).suffix.lower() in (".tif", ".tiff"):
            import tifffile

            with tifffile.TiffFile(path) as tif:
                shape = tif.pages[0].shape
        else:
            from PIL import Image

            with Image.open(path) as im:
                shape = (im.height, im.width, len(im.getbands()))
    except Exception:  # noqa: BLE001  (unreadable: the command itself says why)
        return False
    channels = shape[2] if len(shape) > 2 else 1
    return exceeds_device(shape, 2 * channels, device)


def device_chunks(channels: int, depth: int, device=None, factor: int = 2) -> int:
    """A tile side whose padded tile (with its margins) needs at most a quarter of the
    device's largest allocation, in `factor` fields' worth."""
    limit = get_runtime(device).device.max_mem_alloc_size // 4
    side = int(np.sqrt(limit / (4 * factor * max(channels, 1))))
    return max(64, side - 2 * depth - 2)
