"""Frequency-selective inpainting: each block of the damage is modelled as a sparse sum of
2-D Fourier basis functions fitted to the known pixels around it, and its missing pixels are
taken from the model.

The design follows the facts published for frequency selective reconstruction (Seiler,
Jonscher, Schoeberl & Kaup, IEEE TIP 2015; Genser, Seiler & Kaup, 2018); the code is our
own and runs on the OpenCL device (kernels/inpainting/spectral.cl has the maths):

- Blocks: the damage's bounding box is cut into `block` x `block` blocks; each block holding
  masked pixels is fitted over an extended window, the block plus `border` pixels on each
  side. Where a window holds less than `split` of known pixels, the block is cut into four
  (down to `min_block`): with the same border, a smaller block sees relatively more of the
  known surroundings, and its model is more local.
- Weights: a known pixel at distance d from the window's centre weighs rho^d (isotropic
  decay); a masked pixel filled by an earlier block weighs delta rho^d (it helps, but is
  trusted less); a pixel still missing weighs 0.
- Model: a weighted least-squares plane through the window (ramps are not periodic), then,
  on the rest, greedy, one Fourier pair per iteration, the one that lowers the weighted squared
  error most times a prior (1 - |k| / |k|max)^alpha that favours low frequencies; each pick
  adds only gamma of its coefficient (orthogonality-deficiency compensation: the basis is
  not orthogonal under the weights, so a full step overshoots); the residual's transform is
  updated in the frequency domain by a convolution with the weight's transform, so that an
  iteration costs O(L^2), not a new transform.
- Order: blocks with the larger share of known pixels in their windows go first (filled
  pixels count delta); a wave is every pending block that comes first among the blocks its
  window touches, so the blocks of a wave are independent and run in one launch, one
  work-group per block (its channels in turn: the weights' transform and the candidates'
  factors are shared), in place. The order is planned on the host from the mask alone
  before anything runs; the device never waits for the host between waves.
- Cycle spinning: `shifts` block grids, offset by half a block, are filled independently
  (each in its own copy of the crop; their waves share launches) and averaged: the blocks'
  seams and each grid's unlucky cuts average out.
- Colour: several channels are fitted in a decorrelated basis (principal axes of the known
  pixels near the damage), each channel on its own, and turned back afterwards.
- Programs: one (per dtype); image size, channel count, block sizes and every option are
  kernel arguments, and the work-group size is fixed, so nothing is built per call.
- Precision: the data stays float (float32, or float64 with dtype=float64) from the input's
  scaling to the output; nothing is quantised to 8 bits.
- Only the damage's blocks are touched: the upload is the damage's bounding box grown by the
  border, and the kernel writes masked pixels only.

Defaults (block 8, border 12, rho 0.6, gamma 0.7, alpha 2, delta 1, split 0.3, two grids,
100 picks) were chosen on calibration photos only, with benchmarks/inpaint_spectral_quick.py.
"""

from __future__ import annotations

import time

import numpy as np
import pyopencl as cl

from ..imagedata import InputError

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/spectral.cl",)

DESCRIPTION = (
    "frequency-selective: each block of the hole a sparse sum of Fourier basis "
    "functions fitted to the known pixels around it"
)

# None: the whole image is one call, so that every block of the damage, wherever it lies,
# goes into the same few launches (one per wave) instead of a launch per component.
MARGIN = None

MAXL = 32  # kernels/inpainting/spectral.cl's SPECTRAL_MAXL
MAXK = 512  # its SPECTRAL_MAXK
GROUP = 64  # its SPECTRAL_GROUP
COLOURS = ("pca", "channels")


def _check(block, min_block, border, split, rho, delta, gamma, alpha, iterations, stop, colour):
    for name, v in (
        ("block", block),
        ("min_block", min_block),
        ("border", border),
        ("iterations", iterations),
    ):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise InputError(f"{name} must be an integer >= 1, not {v!r}")
    if block % 2 or min_block % 2:
        raise InputError(
            f"block and min_block must be even (the window's centre), not {block} and {min_block}"
        )
    if min_block > block or block % min_block or (block // min_block) & (block // min_block - 1):
        raise InputError(
            f"min_block={min_block} must be block={block} halved zero or more "
            "times (blocks are split in four)"
        )
    if block + 2 * border > MAXL:
        raise InputError(
            f"block + 2 * border = {block + 2 * border} exceeds the largest window "
            f"{MAXL}; use a smaller block or border"
        )
    if iterations > MAXK:
        raise InputError(f"iterations={iterations} exceeds {MAXK}; use fewer")
    for name, v, lo, hi in (
        ("rho", rho, 0.0, 1.0),
        ("delta", delta, 0.0, 1.0),
        ("gamma", gamma, 0.0, 1.0),
        ("split", split, 0.0, 1.0),
    ):
        if not (np.isfinite(v) and lo <= v <= hi) or (name in ("rho", "gamma") and v == 0):
            raise InputError(f"{name} must be a number in ({lo:g}, {hi:g}], not {v!r}")
    if not (np.isfinite(alpha) and alpha >= 0):
        raise InputError(f"alpha must be a number >= 0, not {alpha!r}")
    if not (np.isfinite(stop) and 0 <= stop < 1):
        raise InputError(f"stop must be a number in [0, 1), not {stop!r}")
    if colour not in COLOURS:
        raise InputError(f"colour must be one of {', '.join(COLOURS)}, not {colour!r}")


# ---------------------------------------------------------------------------------------
# The plan: blocks, their sizes and their waves, from the mask alone


def _window_sums(weight: np.ndarray, border: int, ys, xs, sizes) -> np.ndarray:
    """Sum of `weight` over each block's window (the block at (ys, xs), `sizes` wide, grown by
    `border`; outside the array counts 0)."""
    pad = border + MAXL + 1  # windows of blocks past the array's end stay inside
    sat = np.pad(weight, pad).cumsum(0).cumsum(1)
    # the window's rows [y - border, y + size + border) are pad's [a, b) with a = y - border +
    # pad; sat is inclusive, so the sum is sat[b - 1] - sat[a - 1] (likewise for columns)
    a_y, a_x = ys - border + pad - 1, xs - border + pad - 1
    b_y, b_x = ys + sizes + border + pad - 1, xs + sizes + border + pad - 1
    return sat[b_y, b_x] - sat[a_y, b_x] - sat[b_y, a_x] + sat[a_y, a_x]


def plan(
    omega: np.ndarray,
    *,
    block: int = 8,
    min_block: int = 4,
    border: int = 12,
    split: float = 0.3,
    delta: float = 1.0,
    shift: tuple = (0, 0),
):
    """The blocks and their waves for a mask.

    Parameters
    ----------
    omega : np.ndarray
        bool (rows, cols), True where to fill.
    block, min_block, border, split, delta : int, int, int, float, float
        As for `solve`.
    shift : tuple
        (rows, columns) by which the block grid starts before the damage's bounding box.

    Returns
    -------
    crop : tuple
        (y0, y1, x0, x1), the part of the image that the windows reach.
    blocks : np.ndarray
        int32 (n, 4): row, column (in the crop; < 0 where a block starts before the image),
        size B, window L of each block, wave by wave.
    waves : list
        (first, count) of each wave in `blocks`.
    wave_of : np.ndarray
        int32 over the crop: -1 for known pixels, else the wave that fills the pixel.
    """
    ny, nx = omega.shape
    rows, cols = np.flatnonzero(omega.any(1)), np.flatnonzero(omega.any(0))
    if rows.size == 0:
        return (0, 0, 0, 0), np.zeros((0, 4), np.int32), [], np.zeros((0, 0), np.int32)
    gy0, gx0 = rows[0] - shift[0], cols[0] - shift[1]  # the block grid's origin (may be < 0)
    gy = -(-(rows[-1] + 1 - gy0) // block)
    gx = -(-(cols[-1] + 1 - gx0) // block)
    cy0, cx0 = max(0, gy0 - border), max(0, gx0 - border)
    cy1 = min(ny, gy0 + gy * block + border)
    cx1 = min(nx, gx0 + gx * block + border)
    hole = omega[cy0:cy1, cx0:cx1]
    oy, ox = gy0 - cy0, gx0 - cx0  # the block grid's origin in the crop
    # the hole on the grid of the smallest blocks (cells), padded to whole top blocks
    cell = min_block
    ncy, ncx = gy * (block // cell), gx * (block // cell)
    grid = np.zeros((ncy * cell, ncx * cell), bool)
    ya, xa = max(0, -oy), max(0, -ox)  # grid rows and columns above / left of the image
    part = hole[oy + ya : oy + ncy * cell, ox + xa : ox + ncx * cell]
    grid[ya : ya + part.shape[0], xa : xa + part.shape[1]] = part
    cells = grid.reshape(ncy, cell, ncx, cell).any((1, 3))
    known = (~hole).astype(np.float64)

    # sizes: a block whose window holds less than `split` of known pixels is cut in four
    found = []  # (cell row, cell col, size in cells)
    todo = [
        (i * (block // cell), j * (block // cell), block // cell)
        for i in range(gy)
        for j in range(gx)
    ]
    while todo:
        cys = np.array([t[0] for t in todo])
        cxs = np.array([t[1] for t in todo])
        sz = np.array([t[2] for t in todo])
        has = np.array([cells[a : a + s, b : b + s].any() for a, b, s in todo], bool)
        area = (sz * cell + 2 * border) ** 2
        share = _window_sums(known, border, oy + cys * cell, ox + cxs * cell, sz * cell) / area
        nxt = []
        for (a, b, s), h, sh in zip(todo, has, share, strict=True):
            if not h:
                continue
            if sh < split and s > 1:
                h2 = s // 2
                nxt += [(a, b, h2), (a, b + h2, h2), (a + h2, b, h2), (a + h2, b + h2, h2)]
            else:
                found.append((a, b, s))
        todo = nxt
    n = len(found)
    fy = np.array([f[0] for f in found])
    fx = np.array([f[1] for f in found])
    fs = np.array([f[2] for f in found])
    label = np.full((ncy, ncx), -1, np.int64)  # which block owns each cell
    for i, (a, b, s) in enumerate(found):
        label[a : a + s, b : b + s] = i
    reach = -(-border // cell)  # cells a window reaches beyond its block
    py, px, ps = oy + fy * cell, ox + fx * cell, fs * cell
    # neighbours: j's pixels lie in i's window (and i's in j's: the relation is symmetric);
    # neighbours never share a wave, and a filled block adds to its neighbours' scores
    pi, pj = [], []
    for i, (a, b, s) in enumerate(found):
        near = np.unique(
            label[max(0, a - reach) : a + s + reach, max(0, b - reach) : b + s + reach]
        )
        near = near[(near >= 0) & (near != i)]
        pi.append(np.full(near.size, i))
        pj.append(near)
    pi, pj = np.concatenate(pi).astype(np.int64), np.concatenate(pj).astype(np.int64)
    pad = border + MAXL + 1
    hole_sat = np.pad(hole.astype(np.int64), pad).cumsum(0).cumsum(1)

    def count(sat, y0, y1, x0, x1):  # sum over rows [y0, y1), columns [x0, x1) of the crop
        y1, x1 = np.maximum(y1, y0), np.maximum(x1, x0)
        a_y, a_x, b_y, b_x = y0 + pad - 1, x0 + pad - 1, y1 + pad - 1, x1 + pad - 1
        return sat[b_y, b_x] - sat[a_y, b_x] - sat[b_y, a_x] + sat[a_y, a_x]

    known_sat = np.pad((~hole).astype(np.int64), pad).cumsum(0).cumsum(1)
    known_n = count(known_sat, py - border, py + ps + border, px - border, px + ps + border)
    # hole pixels of j inside i's window: they count delta once j is filled
    overlap = count(
        hole_sat,
        np.maximum(py[pj], py[pi] - border),
        np.minimum(py[pj] + ps[pj], py[pi] + ps[pi] + border),
        np.maximum(px[pj], px[pi] - border),
        np.minimum(px[pj] + ps[pj], px[pi] + ps[pi] + border),
    )
    area = (ps + 2 * border) ** 2
    filled_n = np.zeros(n, np.int64)
    block_wave = np.full(n, -1, np.int64)
    pending = np.ones(n, bool)
    order, waves = [], []
    while pending.any():
        idx = np.flatnonzero(pending)
        score = (known_n[idx] + delta * filled_n[idx]) / area[idx]
        # unique ranks: the larger score first, then the lower index
        rank = np.full(n, -1, np.int64)
        rank[idx[np.lexsort((-idx, score))]] = np.arange(idx.size)
        live = pending[pi] & pending[pj]
        pi, pj, overlap = pi[live], pj[live], overlap[live]
        best_near = np.full(n, -1, np.int64)
        np.maximum.at(best_near, pi, rank[pj])
        ok = (score > 0) | (score.max() <= 0)
        chosen = idx[(rank[idx] > best_near[idx]) & ok]
        block_wave[chosen] = len(waves)
        waves.append((len(order), chosen.size))
        order.extend(chosen.tolist())
        pending[chosen] = False
        done = ~pending[pj]
        np.add.at(filled_n, pi[done], overlap[done])
    order = np.array(order, np.int64)
    blocks = np.stack([py[order], px[order], ps[order], ps[order] + 2 * border], 1)
    wave_of = np.full(hole.shape, -1, np.int32)
    hy, hx = np.nonzero(hole)
    wave_of[hy, hx] = block_wave[label[(hy - oy) // cell, (hx - ox) // cell]]
    return (cy0, cy1, cx0, cx1), blocks.astype(np.int32), waves, wave_of


# ---------------------------------------------------------------------------------------
# Colour


def colour_axes(data: np.ndarray, known: np.ndarray):
    """(mean, axes): the principal axes of the known pixels' colours, as rows of an
    orthonormal matrix, so that axes @ (colour - mean) decorrelates the channels."""
    nc = data.shape[0]
    values = data[:, known]
    if values.shape[1] > 200_000:  # a spread subsample estimates a 3 x 3 covariance as well
        values = values[:, :: values.shape[1] // 200_000 + 1]
    mean = values.mean(1)
    if values.shape[1] < 2:
        return mean, np.eye(nc)
    cov = np.cov(values)
    _, vecs = np.linalg.eigh(np.atleast_2d(cov))
    return mean, vecs[:, ::-1].T


# ---------------------------------------------------------------------------------------
# The fill


def block_iterations(blocks, hole, iterations: int, per_pixel: float) -> np.ndarray:
    """Each block's most picks: `iterations`, or with per_pixel > 0, per_pixel picks for each
    of its hole pixels (at least 4), whichever is fewer: a speck needs fewer terms than a
    block-wide hole."""
    if per_pixel <= 0:
        return np.full(len(blocks), iterations, np.int32)
    pad = MAXL
    sat = np.pad(hole.astype(np.int64), pad).cumsum(0).cumsum(1)
    y, x, s = blocks[:, 0] + pad - 1, blocks[:, 1] + pad - 1, blocks[:, 2]
    holes = sat[y + s, x + s] - sat[y, x + s] - sat[y + s, x] + sat[y, x]
    return np.minimum(iterations, np.maximum(4, np.ceil(per_pixel * holes))).astype(np.int32)


def shifts_of(shifts: int, block: int) -> list:
    """The block grids' offsets: 1, 2 (a half block diagonally) or 4 (every half block)."""
    h = block // 2
    return {1: [(0, 0)], 2: [(0, 0), (h, h)], 4: [(0, 0), (0, h), (h, 0), (h, h)]}[shifts]


def fill(
    data: np.ndarray,
    omega: np.ndarray,
    runtime,
    *,
    dtype=np.float32,
    block: int = 8,
    min_block: int = 4,
    border: int = 12,
    split: float = 0.3,
    rho: float = 0.6,
    delta: float = 1.0,
    gamma: float = 0.7,
    alpha: float = 2.0,
    iterations: int = 100,
    stop: float = 0.0,
    colour: str = "pca",
    detrend: bool = True,
    shifts: int = 2,
    cutoff: float = 1.5,
    per_pixel: float = 0.0,
    timings: dict | None = None,
) -> np.ndarray:
    """Frequency-selective fill of (channels, rows, cols) float data (the module docstring has
    the method; `clpde.inpaint(..., method="spectral")` is the user's way in).

    Parameters
    ----------
    data : np.ndarray
        (channels, rows, cols) floats; values inside omega are ignored.
    omega : np.ndarray
        bool (rows, cols), True where to fill.
    runtime : clpde.runtime.Runtime
        The OpenCL device.
    dtype : numpy dtype
        The device's arithmetic, float32 or float64.
    block, min_block : int
        Largest and smallest block side (even; min_block is block halved zero or more times).
    border : int
        The window's reach beyond its block; block + 2 border <= 32.
    split : float
        A block whose window holds less than this share of known pixels is cut in four.
    rho : float
        Weight decay per pixel of distance from the window's centre, in (0, 1].
    delta : float
        Weight of pixels filled by earlier blocks, in [0, 1].
    gamma : float
        Share of each pick's coefficient taken, in (0, 1].
    alpha : float
        Power of the low-frequency prior (1 - |k| / |k|max)^alpha, >= 0.
    iterations : int
        Most picks per block and channel (<= 512).
    stop : float
        End a block once a pick lowers the error by less than this share of the first one's.
    colour : str
        'pca' fits the principal axes of the known colours, 'channels' the channels as given.
    detrend : bool
        Take a weighted least-squares plane out of each window before the Fourier picks.
    shifts : int
        1, 2 or 4 block grids, offset by half a block, whose fills are averaged.
    cutoff : float
        Candidate frequencies |k| <= cutoff x Nyquist; 1.5 takes all.
    per_pixel : float
        > 0: a block's picks are at most this many per hole pixel in it (at least 4).
    timings : dict or None
        Receives the seconds spent planning, building, uploading, running the waves and
        reading back, and the counts of blocks and launches.

    Returns
    -------
    np.ndarray
        float64 array of data's shape, equal to data outside omega.

    Raises
    ------
    InputError
        For options out of range, or a mask that covers every pixel.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.runtime import get_runtime
    >>> y, x = np.mgrid[0:48, 0:48]
    >>> data = (0.2 + 0.5 * x / 48 + 0.1 * y / 48)[None]
    >>> omega = np.zeros((48, 48), bool)
    >>> omega[20:24, 8:40] = True
    >>> out = fill(data, omega, get_runtime())
    >>> bool(np.abs(out - data)[:, omega].max() < 0.02)
    True
    """
    _check(block, min_block, border, split, rho, delta, gamma, alpha, iterations, stop, colour)
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise InputError(
            f"cutoff must be a number > 0 (a share of the Nyquist frequency), not {cutoff!r}"
        )
    if not (np.isfinite(per_pixel) and per_pixel >= 0):
        raise InputError(f"per_pixel must be a number >= 0, not {per_pixel!r}")
    if shifts not in (1, 2, 4):
        raise InputError(f"shifts must be 1, 2 or 4 (block grids averaged), not {shifts!r}")
    data = np.asarray(data)
    omega = np.asarray(omega, bool)
    out = np.array(data, np.float64, copy=True)
    if not omega.any():
        return out
    if omega.all():
        raise InputError(
            "the mask covers every pixel, so nothing is known to inpaint from; "
            "mark only the damaged region"
        )
    t = {} if timings is None else timings
    t0 = time.perf_counter()
    plans = [
        plan(
            omega,
            block=block,
            min_block=min_block,
            border=border,
            split=split,
            delta=delta,
            shift=sh,
        )
        for sh in shifts_of(shifts, block)
    ]
    # every grid's copy of the image is one crop, the union of theirs; the copies' waves run
    # together (wave w of every grid in launch w), each block in its own copy
    y0 = min(p[0][0] for p in plans)
    y1 = max(p[0][1] for p in plans)
    x0 = min(p[0][2] for p in plans)
    x1 = max(p[0][3] for p in plans)
    part = out[:, y0:y1, x0:x1]
    hole = omega[y0:y1, x0:x1]
    nc = part.shape[0]
    ncopy = len(plans)
    if colour == "pca" and nc > 1:
        mean, axes = colour_axes(part, ~hole)
    else:
        mean, axes = np.zeros(nc), np.eye(nc)
    work = np.einsum("ij,jyx->iyx", axes, part - mean[:, None, None])
    work[:, hole] = 0.0  # unknown values never enter (their weight is 0), NaN must not either
    real = np.dtype(dtype)
    host = np.ascontiguousarray(np.broadcast_to(work, (ncopy,) + work.shape), real)
    wave_of = np.full((ncopy,) + hole.shape, -1, np.int32)
    per_wave = {}
    for c, ((cy0, cy1, cx0, cx1), blocks, waves, w_of) in enumerate(plans):
        wave_of[c, cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0] = w_of
        moved = blocks + np.array([cy0 - y0, cx0 - x0, 0, 0], np.int32)
        picks = block_iterations(blocks, omega[cy0:cy1, cx0:cx1], iterations, per_pixel)
        for w, (first, count) in enumerate(waves):
            rows = np.concatenate(
                [
                    moved[first : first + count],
                    np.full((count, 1), c, np.int32),
                    picks[first : first + count, None],
                ],
                1,
            )
            per_wave.setdefault(w, []).append(rows)
    order = [np.concatenate(per_wave[w]) for w in range(len(per_wave))]
    all_blocks = np.ascontiguousarray(np.concatenate(order), np.int32)
    starts = np.cumsum([0] + [len(o) for o in order])
    t["plan"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    kernel = runtime.kernel("inpainting/spectral.cl", "spectral_blocks", real)
    t["build"] = time.perf_counter() - t0

    q = runtime.queue
    t0 = time.perf_counter()
    mf = cl.mem_flags
    img = cl.Buffer(runtime.ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=host)
    waves_buf = cl.Buffer(runtime.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=wave_of)
    blocks_buf = cl.Buffer(runtime.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=all_blocks)
    q.finish()
    t["upload"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    s = real.type
    ny, nx = hole.shape
    for w in range(len(order)):
        kernel(
            q,
            (len(order[w]) * GROUP,),
            (GROUP,),
            img,
            waves_buf,
            blocks_buf,
            np.int32(starts[w]),
            np.int32(w),
            np.int32(nx),
            np.int32(ny),
            np.int32(nc),
            s(rho),
            s(delta),
            s(gamma),
            s(alpha),
            s(stop),
            np.int32(bool(detrend)),
            s(cutoff),
        )
    q.finish()
    t["waves"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    cl.enqueue_copy(q, host, img)
    q.finish()
    t["readback"] = time.perf_counter() - t0
    t["blocks"], t["launches"] = len(all_blocks), len(order)
    model = host.astype(np.float64).mean(0)  # the grids' average
    filled = np.einsum("ji,jyx->iyx", axes, model) + mean[:, None, None]
    part[:, hole] = filled[:, hole]
    return out


def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    block=8,
    min_block=4,
    border=12,
    split=0.3,
    rho=0.6,
    delta=1.0,
    gamma=0.7,
    alpha=2.0,
    iterations=100,
    stop=0.0,
    colour="pca",
    detrend=True,
    shifts=2,
    cutoff=1.5,
    per_pixel=0.0,
):
    """Registry entry point: frequency-selective inpainting (see the module docstring).

    Options: block (largest block, even), min_block (smallest, block halved), border (the
    window's reach beyond its block; block + 2 border <= 32), split (a block whose window
    holds less known than this share is cut in four), rho (weight decay per pixel of
    distance), delta (weight of pixels filled earlier), gamma (share of each pick's
    coefficient taken), alpha (the low-frequency prior's power), iterations (most picks per
    block), stop (end a block once a pick lowers the error less than this share of the
    first one), colour ('pca': decorrelated channels, 'channels': as given), detrend (fit
    a plane to each window first and model the rest), shifts (1, 2 or 4 block grids, offset
    by half a block, whose fills are averaged), cutoff (the candidate frequencies: |k| at most
    this share of the Nyquist frequency; 1.5 takes all), per_pixel (> 0: a block's picks are
    at most this many per hole pixel in it, at least 4).
    """
    return fill(
        data,
        omega,
        runtime,
        dtype=dtype,
        block=block,
        min_block=min_block,
        border=border,
        split=split,
        rho=rho,
        delta=delta,
        gamma=gamma,
        alpha=alpha,
        iterations=iterations,
        stop=stop,
        colour=colour,
        detrend=detrend,
        shifts=shifts,
        cutoff=cutoff,
        per_pixel=per_pixel,
    )
