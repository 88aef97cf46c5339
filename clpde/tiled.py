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

from ._state import renamed_keyword
from ._validation import check_steps
from .imagedata import InputError, compute_dtype, to_kernel_layout
from .planar import FLOWS, PlanarFlow
from .runtime import get_runtime

RADIUS = 1  # every planar.cl and rof.cl step reads the 3x3 neighbourhood only
# Tiled denoise_tv runs exactly `steps` iterations; a tolerance no change falls below.
_NEVER = 1e-300


class _ScaledFlow(PlanarFlow):
    """A PlanarFlow on data already in the kernels' layout and [0, 1] scale."""

    def __init__(self, data, flow, dt, device, precision, params):
        from .fields import Field, Grid, PingPong

        self.runtime = get_runtime(device)
        nc, ny, nx = data.shape
        self.grid = Grid(self.runtime, nx, ny, nc, 1, np.dtype(precision or np.float32))
        self.flow, self.steps_done, self.time = flow, 0, 0.0
        self.pair = PingPong(Field.from_host(self.grid, data))
        self._setup(flow, dt, params.get("kappa", 0.05), params.get("edge", "exp"),
                    params.get("eps"), None, params.get("presmooth"))


def _tile_diffuse(block, flow, steps, dt, device, precision, params):
    state = _ScaledFlow(block, flow, dt, device, precision, params)
    return state.run(steps, progress=False).pair.cur.to_host().astype(np.float64)


def _tile_denoise(block, lam, steps, check_every, device, precision, vectorial=False):
    from .fields import Grid
    from .rof import _primal_dual

    runtime = get_runtime(device)
    nc, ny, nx = block.shape
    grid = Grid(runtime, nx, ny, nc, 1, compute_dtype(block.dtype, precision))
    u, *_ = _primal_dual(grid, block, np.full(nc, lam), None, steps, _NEVER, check_every, False,
                         vectorial)
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
    out = array.map_overlap(func, depth={0: 0, 1: depth, 2: depth}, boundary="none",
                            dtype=np.float64, meta=np.empty((0, 0, 0)), **kwargs)
    # One device per process: the tiles run one after another here, each on the device.
    with dask.config.set(scheduler="synchronous"):
        return out.compute()


def diffuse(image, flow: str = "heat", steps: int = 100, dt=None, channel_axis=None,
            device=None, *, chunks=256, dtype=None, precision=None, **params) -> np.ndarray:
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
        from .planar import gaussian_weights

        radius += len(gaussian_weights(float(params["presmooth"]))) - 1
    out = _chunked(data, chunks, steps * radius, _tile_diffuse, flow=flow, steps=steps, dt=dt,
                   device=runtime.index,
                   precision=renamed_keyword("dtype", dtype, "precision", precision),
                   params=params)
    return layout.restore(out)


def denoise_tv(image, weight, steps: int, channel_axis=None, *, device=None, chunks=256,
               check_every: int = 5, dtype=None, precision=None,
               vectorial: bool | None = None) -> np.ndarray:
    """clpde.denoise_tv (primal-dual, given weight) for exactly `steps` iterations, tile by
    tile; bitwise equal to ``clpde.denoise_tv(image, weight=weight, max_steps=steps,
    tol=1e-300, check_every=check_every, vectorial=vectorial)`` (vectorial by default for
    several channels, as there: its coupling is per cell, so the reach is the same)."""
    from .imagedata import positive

    steps = check_steps(steps)
    data, layout = to_kernel_layout(image, channel_axis)
    weight_unit = 1.0 if np.issubdtype(layout.dtype, np.integer) else layout.scale
    lam = weight_unit / positive("weight", weight)
    runtime = get_runtime(device)
    # u = f + div(p)/lambda adds one more cell to the iterations' reach.
    vectorial = data.shape[0] > 1 if vectorial is None else bool(vectorial)
    out = _chunked(data, chunks, steps * RADIUS + 1, _tile_denoise, lam=lam, steps=steps,
                   vectorial=vectorial,
                   check_every=max(1, int(check_every)), device=runtime.index,
                   precision=renamed_keyword("dtype", dtype, "precision", precision))
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


def run_tiled_command(args, force: bool = False) -> bool:
    """Run parsed `clpde diffuse` / `clpde denoise` arguments tiled when asked (force) or
    needed (the image exceeds the device); False when the untiled command should run."""
    from .cli._common import load_input, save_output, split_alpha

    command = args.command
    image = load_input(args)
    parts = split_alpha(image, args.input)
    channels = 1 if parts.channel_axis is None else parts.colour.shape[-1]
    factor = 2 if command == "diffuse" else 4  # denoise: f, u and a two-component dual field
    needed = exceeds_device(parts.colour.shape, channels * factor // 2, args.device)
    if not (force or needed):
        return False
    if command == "diffuse":
        params = {k: getattr(args, k) for k in ("kappa", "edge", "eps", "presmooth")
                  if getattr(args, k) is not None}
        chunks = 256 if not needed else device_chunks(channels, args.steps, args.device)
        result = diffuse(parts.colour, args.flow, steps=args.steps, dt=args.dt,
                         channel_axis=parts.channel_axis, device=args.device, chunks=chunks,
                         **params)
    else:
        if args.weight is None or args.method != "primal-dual" or args.max_steps is None:
            raise InputError("tiled denoise needs --weight W and --max-steps N (a fixed "
                             "iteration count) with --method primal-dual")
        chunks = 256 if not needed else device_chunks(channels, args.max_steps, args.device, 4)
        result = denoise_tv(parts.colour, args.weight, args.max_steps,
                            channel_axis=parts.channel_axis, device=args.device, chunks=chunks,
                            vectorial=False if getattr(args, "per_channel", False) else None)
    save_output(args, parts.join(result))
    return True


# ---- large images in bounded memory: the untiled API's own paths ------------------------
# clpde.diffuse and clpde.denoise_tv take these paths for images of more values than this
# (channels x rows x columns): below it the whole image in float64 and its device fields
# cost little; above it they cost tens of times the image (a 6000 x 4000 colour photo:
# several GB), and these paths keep to a fixed budget whatever the image's size.
LARGE_VALUES = 1 << 22
# Rows converted or restored at a time: float64 temporaries of a strip, not of the image.
_STRIP_ROWS = 256
# denoise_tv's tiles: the kept core, and the margin on each side of it. A margin of 64
# keeps every kept pixel at least 64 px from a tile border that is not the image's own;
# the per-pixel stopping test makes a part of an image converge as it would on its own,
# so pixels that far in match the whole image's result (tests/planar/test_rof.py checks
# 60 px in).
TILE_CORE = 1024
TILE_MARGIN = 64
# With sigma, lambda is fitted on the image's central region of at most this many values.
LAMBDA_SAMPLE_VALUES = LARGE_VALUES


class _Scaled:
    """An image's channels, converted to the kernels' [0, 1] float64 on demand, a block at
    a time, with the whole image's offset and scale (as to_kernel_layout converts it: the
    same arithmetic per value, so the same numbers), and restored into an output array of
    the input's shape and dtype."""

    def __init__(self, image, channel_axis):
        from .imagedata import (
            ImageLayout,
            as_image,
            check_channel_axis,
            integer_range,
            value_range,
        )

        array = as_image(image)
        axis = check_channel_axis(array.ndim, channel_axis)
        if np.issubdtype(array.dtype, np.integer):
            offset, scale = integer_range(array.dtype)
        else:
            offset, scale = value_range(float(array.min()), float(array.max()))
        self.array = array
        self.channels = array[np.newaxis] if axis is None else np.moveaxis(array, axis, 0)
        self.nc, self.ny, self.nx = self.channels.shape
        if min(self.ny, self.nx) < 1:
            raise InputError(f"image has no pixels (shape {array.shape})")
        self.layout = ImageLayout(array.shape, array.dtype, axis, offset, scale)
        self._strip = ImageLayout((), array.dtype, None, offset, scale)
        self.out = np.empty_like(array)
        self.out_channels = (self.out[np.newaxis] if axis is None
                             else np.moveaxis(self.out, axis, 0))

    def block(self, rows: slice, cols: slice, channel=None) -> np.ndarray:
        """(nc, h, w) float64 of one block (all channels, or one)."""
        c = slice(None) if channel is None else slice(channel, channel + 1)
        data = self.channels[c, rows, cols]
        return (data.astype(np.float64) - self.layout.offset) / self.layout.scale

    def restore_value(self, value: float):
        """One kernel value restored as an output value."""
        return self._strip.restore(np.full((1, 1, 1), value))[0, 0]

    def restore(self, values: np.ndarray, rows: slice, cols: slice, channel=None) -> None:
        """Write (nc, h, w) kernel values (or (h, w) of one channel) into the output, strip
        by strip, with ImageLayout.restore's arithmetic."""
        values = values.reshape((-1,) + values.shape[-2:])
        channels = range(self.nc) if channel is None else [channel]
        for k, c in enumerate(channels):
            for r in range(0, values.shape[1], _STRIP_ROWS):
                part = values[k, r:r + _STRIP_ROWS]
                start = rows.start + r
                self.out_channels[c, start:start + part.shape[0], cols] = \
                    self._strip.restore(part[np.newaxis])


def is_large(image, channel_axis=None) -> bool:
    """Whether an image has more values than LARGE_VALUES (channels included)."""
    return int(np.prod(np.shape(image))) > LARGE_VALUES


def diffuse_by_channel(image, flow, steps, dt, channel_axis, device, precision, progress,
                       params):
    """clpde.diffuse one channel at a time, converting and restoring in strips: bit for bit
    the whole-image result (every flow of planar.cl acts on each channel alone, with the
    same arithmetic per cell), in the memory of one channel's two device fields.
    Returns (result, the last channel's flow)."""
    from .fields import Field, Grid, PingPong

    scaled = _Scaled(image, channel_axis)
    runtime = get_runtime(device)
    dtype = np.dtype(precision or np.float32)
    grid = Grid(runtime, scaled.nx, scaled.ny, 1, 1, dtype)
    state = None
    for c in range(scaled.nc):
        padded = np.zeros(grid.padded_shape, dtype)
        for r in range(0, scaled.ny, _STRIP_ROWS):
            rows = slice(r, min(r + _STRIP_ROWS, scaled.ny))
            padded[0, 1 + rows.start:1 + rows.stop, 1:-1] = scaled.block(rows, slice(None), c)[0]
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
        self._setup(flow, dt, params.get("kappa", 0.05), params.get("edge", "exp"),
                    params.get("eps"), params.get("weight"), params.get("presmooth"))


def noise_std_by_strips(scaled: _Scaled) -> np.ndarray:
    """rof._noise_std of each channel, from the residual computed a strip at a time: the
    same float64 values (each residual value reads the same nine numbers in the same order),
    so the same median, without the whole image's float64 copy and its temporaries."""
    from .rof import _MAD_TO_STD, _NOISE_MASK

    ny, nx = scaled.ny, scaled.nx
    if ny < 3 or nx < 3:
        raise InputError(f"an image of {nx}x{ny} pixels is too small to estimate its noise "
                         "from; give sigma or weight")
    sig = np.empty(scaled.nc)
    for c in range(scaled.nc):
        residual = np.empty((ny - 2, nx - 2))
        for r in range(0, ny - 2, _STRIP_ROWS):
            stop = min(r + _STRIP_ROWS, ny - 2)
            u = scaled.block(slice(r, stop + 2), slice(None), c)[0]
            h = stop - r
            residual[r:stop] = sum(_NOISE_MASK[i, j] * u[i:h + i, j:nx - 2 + j]
                                   for i in range(3) for j in range(3))
        np.abs(residual, out=residual)
        sig[c] = float(np.median(residual)) * _MAD_TO_STD / 6.0
    return sig


def _spans(n: int, core: int, margin: int):
    """(kept, read) slices along one axis: kept cores of `core` cells, each read with
    `margin` more on each side where the image has them."""
    for start in range(0, n, core):
        stop = min(start + core, n)
        yield slice(start, stop), slice(max(0, start - margin), min(n, stop + margin))


def denoise_large(scaled: _Scaled, grid_dtype, runtime, lam0, sigma2, max_steps, tol,
                  check_every, progress, vectorial):
    """denoise_tv of a large image in overlapping tiles (TILE_CORE kept, TILE_MARGIN read on
    each side), each run to its own convergence with one lambda per channel for the whole
    image. With sigma, lambda is first fitted (the dynamic update) on the central region
    of the image of LAMBDA_SAMPLE_VALUES values, then held for every tile.

    Not bit for bit the whole-image run: a tile's pixels see the image only to TILE_MARGIN
    beyond its core and stop by their own convergence; the fitted lambda is that of the
    central region, not of the whole image. Returns (result, steps (the most a tile ran),
    converged (every tile), lambda, residual variance per channel in [0, 1] units)."""
    from .fields import Grid
    from .rof import _primal_dual

    nc, ny, nx = scaled.nc, scaled.ny, scaled.nx
    lam = np.asarray(lam0, np.float64) if lam0 is not None else None
    if sigma2 is not None:
        side = int(np.sqrt(LAMBDA_SAMPLE_VALUES / nc))
        h, w = min(ny, side), min(nx, side)
        rows = slice((ny - h) // 2, (ny - h) // 2 + h)
        cols = slice((nx - w) // 2, (nx - w) // 2 + w)
        sample = scaled.block(rows, cols)
        grid = Grid(runtime, w, h, nc, 1, grid_dtype)
        _, _, _, lam = _primal_dual(grid, sample, 1.0 / np.sqrt(sigma2), sigma2, max_steps,
                                    tol, check_every, False, vectorial)
        del sample
    steps_max, converged = 0, True
    sq = np.zeros(nc)
    tiles = [(ky, kx, ry, rx) for ky, ry in _spans(ny, TILE_CORE, TILE_MARGIN)
             for kx, rx in _spans(nx, TILE_CORE, TILE_MARGIN)]
    from ._progress import progress_bar

    with progress_bar(progress, len(tiles), "clpde denoise_tv", unit="tile") as bar:
        for ky, kx, ry, rx in tiles:
            block = scaled.block(ry, rx)
            grid = Grid(runtime, block.shape[2], block.shape[1], nc, 1, grid_dtype)
            u, steps, done, _ = _primal_dual(grid, block, lam, None, max_steps, tol,
                                             check_every, False, vectorial)
            keep = (slice(None), slice(ky.start - ry.start, ky.stop - ry.start),
                    slice(kx.start - rx.start, kx.stop - rx.start))
            sq += ((u[keep] - block[keep]) ** 2).sum(axis=(1, 2))
            scaled.restore(u[keep], ky, kx)
            steps_max, converged = max(steps_max, steps), converged and done
            bar.update(1)
    return scaled.out, steps_max, converged, lam, sq / (ny * nx)


def channel_moments(scaled: _Scaled) -> tuple[np.ndarray, np.ndarray]:
    """(mean, variance) of each channel in [0, 1] units, summed a strip at a time."""
    mean, var = np.empty(scaled.nc), np.empty(scaled.nc)
    n = scaled.ny * scaled.nx
    for c in range(scaled.nc):
        total = 0.0
        for r in range(0, scaled.ny, _STRIP_ROWS):
            total += float(scaled.block(slice(r, r + _STRIP_ROWS), slice(None), c).sum())
        mean[c] = total / n
        sq = 0.0
        for r in range(0, scaled.ny, _STRIP_ROWS):
            block = scaled.block(slice(r, r + _STRIP_ROWS), slice(None), c)
            sq += float(((block - mean[c]) ** 2).sum())
        var[c] = sq / n
    return mean, var
