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
  known surroundings, and its model is more local. Where the damage is thin (text,
  scratches, cracks, dust: no masked pixel farther than THIN from a known one), the border
  is `thin_border`: a smaller window fits such holes as well, and a pick's cost follows
  the window's area.
- Weights: a known pixel at distance d from the window's centre weighs rho^d (isotropic
  decay); a masked pixel filled by an earlier block weighs delta rho^d (it helps, but is
  trusted less); a pixel still missing weighs 0.
- Model: a weighted least-squares plane through the window (ramps are not periodic), then,
  on the rest, greedy, one Fourier pair per iteration, the one that lowers the weighted squared
  error most times a prior (1 - |k| / |k|max)^alpha that favours low frequencies; each pick
  adds only gamma of its coefficient (orthogonality-deficiency compensation: the basis is
  not orthogonal under the weights, so a full step overshoots); the residual's transform is
  updated in the frequency domain by a convolution with the weight's transform, so that an
  iteration costs O(L^2), not a new transform. A channel's picks end once the best pick
  would lower the window's weighted squared residual by less than `stall` of it (the model
  has stalled on what looks like noise), or once that residual's RMS is at most `floor`.
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
  pixels near the damage), each channel on its own, and turned back afterwards; the
  channels after the first (the smaller variances) take `minor` of the picks.
- Programs: one (per dtype and device); image size, channel count, block sizes and every
  option are kernel arguments, and the work-group shape is the device's (work_shape: on
  CPUs one item per block, its candidates in vectors of 8), so nothing is built per call.
- Precision: the data stays float (float32, or float64 with dtype=float64) from the input's
  scaling to the output; nothing is quantised to 8 bits.
- Only the damage's blocks are touched: the upload is the damage's bounding box grown by the
  border, and the kernel writes masked pixels only. `clpde.inpaint` solves each cluster of
  damage in its own box, grown by MARGIN (a block plus the border), so that the host's float
  copy follows the damage too; the blocks of one box share launches, one per wave.

Defaults (block 8, border 12, rho 0.6, gamma 0.7, alpha 2, delta 1, split 0.3, two grids,
100 picks) were chosen on calibration photos only, with benchmarks/inpaint_spectral_quick.py;
the thin border (6: where no damaged pixel is farther than THIN = 4 px from a known one, a
20 px window instead of 32) on the calibration half of the corpus, with
benchmarks/inpaint_spectral_thin.py: on thin damage it takes 2-3x less time at the same
PSNR there; minor 0.3 likewise (every class of the calibration half within 0.015 dB). The
floor is off: 0.004 (one 8-bit level) cost nothing on the calibration half but up to 2 dB
on smooth images of the test half (errors themselves near one level). stall 0.005 was
chosen on the calibration half (docs/inpainting.md, "Picks that stall"): about a fifth
fewer picks, every class within -0.014 / +0.12 dB; 0.01 lost 0.2-0.3 dB on thin damage.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pyopencl as cl
from scipy import ndimage

from ..errors import DeviceLimitError
from ..imagedata import InputError
from ..runtime import enqueue_bare
from .registry import register
from .spectral_options import SpectralOptions
from .spectral_options import check as _check
from .spectral_plan import MAXL, launch_table, plan, shifts_of

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/spectral.cl",)

DESCRIPTION = (
    "frequency-selective: each block of the hole a sparse sum of Fourier basis "
    "functions fitted to the known pixels around it"
)

GROUP = 64  # its SPECTRAL_GROUP on GPUs (work_shape)
CPU_VECTOR = 8  # its SPECTRAL_VW on CPUs: candidates per vector (the only width it takes)
# its SPECTRAL_SCRATCH with vectors (the larger): the REALs of one work-group's windows and
# transforms (W's columns continued to 2 MAXL + 8; R's rows and the candidates' columns
# rounded up to whole vectors), which live in global memory where local memory is too small
# (SPECTRAL_SPILL)
_ROW = (MAXL // 2 + CPU_VECTOR) // CPU_VECTOR * CPU_VECTOR  # a half plane's row, in vectors
_SLOTS = (MAXL // 2 + 1) * (-(-MAXL // CPU_VECTOR) * CPU_VECTOR)  # its columns, in vectors
SCRATCH = 2 * MAXL * MAXL + 2 * MAXL * (2 * MAXL + CPU_VECTOR) + 2 * MAXL * _ROW
SCRATCH += 5 * _SLOTS
SCRATCH_BYTES = 32 * 2**20  # at most this much scratch: larger waves run in several launches
THIN = 4  # px: damage this thin (half-thickness) takes thin_border (text, cracks, dust)
_y, _x = np.mgrid[-THIN : THIN + 1, -THIN : THIN + 1]
DISC = _y**2 + _x**2 <= THIN**2  # a pixel of omega farther than THIN from known survives it


def MARGIN(omega=None, block: int = 8, border: int = 12, **_params) -> int:
    """Known pixels the fill reads around a hole: the block grid starts up to half a block
    before the hole's bounding box and ends less than a block after it, and each window
    reaches `border` beyond its block. Solved in a box grown by this much (clpde.inpaint's
    boxes), a hole's fill reads only its box, so that time and memory follow the damage,
    not the image."""
    for name, v in (("block", block), ("border", border)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise InputError(f"{name} must be an integer >= 1, not {v!r}")
    return int(block) + int(border)


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
    floor: float = 0.0,
    colour: str = "pca",
    detrend: bool = True,
    shifts: int = 2,
    cutoff: float = 1.5,
    per_pixel: float = 0.0,
    thin_border: int = 6,
    minor: float = 0.3,
    stall: float = 0.005,
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
    floor : float
        End a block's channel once the weighted RMS of its window's residual is at most
        this, in the data's units (clpde.inpaint scales data to [0, 1]): picks past it fit
        detail finer than the data's precision.
    stall : float
        End a block's channel once the best pick would lower its window's weighted squared
        residual by less than this share of it, in [0, 1) (0: off).
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
    thin_border : int
        > 0: the border (at most `border`) where the damage is thin (no pixel of omega
        farther than THIN from a known one: text, scratches, cracks, dust); 0: off.
    minor : float
        Share of a block's picks that the channels after the first take, in (0, 1] (at
        least one pick): with colour='pca' they hold the colours' smaller variances.
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
    _check(
        block,
        min_block,
        border,
        split,
        rho,
        delta,
        gamma,
        alpha,
        iterations,
        stop,
        floor,
        colour,
        cutoff,
        per_pixel,
        shifts,
        thin_border,
        minor,
        stall,
    )
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
    if thin_border and thin(omega):
        border = min(border, thin_border)
    grid = {"block": block, "min_block": min_block, "border": border, "split": split}
    plans = [plan(omega, **grid, delta=delta, shift=sh) for sh in shifts_of(shifts, block)]
    # every grid's copy of the image is one crop, the union of theirs; the copies' waves run
    # together (wave w of every grid in launch w), each block in its own copy
    y0 = min(p[0][0] for p in plans)
    y1 = max(p[0][1] for p in plans)
    x0 = min(p[0][2] for p in plans)
    x1 = max(p[0][3] for p in plans)
    part = out[:, y0:y1, x0:x1]
    hole = omega[y0:y1, x0:x1]
    nc = part.shape[0]
    if colour == "pca" and nc > 1:
        mean, axes = colour_axes(part, ~hole)
    else:
        mean, axes = np.zeros(nc), np.eye(nc)
    work = np.einsum("ij,jyx->iyx", axes, part - mean[:, None, None])
    work[:, hole] = 0.0  # unknown values never enter (their weight is 0), NaN must not either
    real = np.dtype(dtype)
    # a writable copy: the device's result is read back into it
    host = np.array(np.broadcast_to(work, (len(plans),) + work.shape), real, order="C")
    table = launch_table(plans, omega, (y0, x0), hole.shape, (iterations, per_pixel, minor))
    t["plan"] = time.perf_counter() - t0
    options = (rho, delta, gamma, alpha, stop, floor, stall, bool(detrend), cutoff)
    _run_waves(runtime, host, table, options, t)
    model = host.astype(np.float64).mean(0)  # the grids' average
    filled = np.einsum("ji,jyx->iyx", axes, model) + mean[:, None, None]
    part[:, hole] = filled[:, hole]
    return out


def thin(omega: np.ndarray) -> bool:
    """Whether no pixel of omega lies farther than THIN from a known pixel."""
    return not ndimage.binary_erosion(omega, DISC, border_value=1).any()


def _run_waves(runtime, host: np.ndarray, table, options, t: dict) -> None:
    """Upload the copies `host` ((copies, channels, rows, cols)), run one launch per wave
    (one work-group per block) and read the copies back into `host`; `t` receives the
    seconds of each stage and the counts of blocks and launches."""
    wave_of, all_blocks, starts = table
    rho, delta, gamma, alpha, stop, floor, stall, detrend, cutoff = options
    real = host.dtype
    t0 = time.perf_counter()
    kernel, spill, group = fitting_kernel(runtime, real)
    t["build"] = time.perf_counter() - t0
    # work-groups per launch: a whole wave, or as many as SCRATCH_BYTES of scratch hold
    widest = int(np.diff(starts).max(initial=1))
    per_launch = max(1, SCRATCH_BYTES // (SCRATCH * real.itemsize)) if spill else widest
    scratch_bytes = min(per_launch, widest) * SCRATCH * real.itemsize if spill else real.itemsize
    runtime.check_alloc(scratch_bytes, "spectral inpainting's scratch memory")

    q = runtime.queue
    t0 = time.perf_counter()
    mf = cl.mem_flags
    img = cl.Buffer(runtime.ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=host)
    waves_buf = cl.Buffer(runtime.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=wave_of)
    blocks_buf = cl.Buffer(runtime.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=all_blocks)
    scratch = cl.Buffer(runtime.ctx, mf.READ_WRITE, scratch_bytes)
    q.finish()
    t["upload"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    s = real.type
    nc, ny, nx = host.shape[1:]
    launches = [
        (w, first, min(per_launch, int(starts[w + 1]) - first))
        for w in range(len(starts) - 1)
        for first in range(int(starts[w]), int(starts[w + 1]), per_launch)
    ]
    # an instance of its own, its arguments set once: a launch sets only its first block and
    # its wave (pyopencl's call sets all 18 each time)
    bare = _bare_kernel(kernel.cl_kernel.program)
    bare.set_args(
        img,
        waves_buf,
        blocks_buf,
        np.int32(0),
        np.int32(0),
        np.int32(nx),
        np.int32(ny),
        np.int32(nc),
        s(rho),
        s(delta),
        s(gamma),
        s(alpha),
        s(stop),
        s(floor * floor),
        s(stall),
        np.int32(detrend),
        s(cutoff),
        scratch,
    )
    for w, first, count in launches:
        bare.set_arg(3, np.int32(first))
        bare.set_arg(4, np.int32(w))
        enqueue_bare(q, bare, (count * group,), (group,), "inpainting/spectral.cl")
    q.finish()
    t["waves"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    cl.enqueue_copy(q, host, img)
    q.finish()
    t["readback"] = time.perf_counter() - t0
    t["blocks"], t["launches"] = len(all_blocks), len(launches)


_BARE = threading.local()


def _bare_kernel(program) -> cl.Kernel:
    """This thread's own instance of spectral_blocks in `program`, made once: a new
    instance and its arguments cost pyopencl 0.23 ms, a kept one's arguments 0.10 (of a
    thin fill's 15). One per thread: a fill sets the instance's arguments, then launches
    it, and another thread's fill must not set them in between."""
    cache = getattr(_BARE, "kernels", None)
    if cache is None:
        cache = _BARE.kernels = {}
    key = program.int_ptr
    if key not in cache:
        cache[key] = (program, cl.Kernel(program, "spectral_blocks"))
    return cache[key][1]


def work_shape(runtime) -> tuple:
    """(SPECTRAL_GROUP, SPECTRAL_VW), the work-group's items and the candidates each item
    updates at once: on GPUs GROUP items share a block's candidates one at a time; on CPUs
    one item walks them in vectors of CPU_VECTOR (PoCL runs a work-group's items in turn, so
    there items buy nothing, and its compiler leaves the scalar loop unvectorised)."""
    return (1, CPU_VECTOR) if runtime.is_cpu else (GROUP, 1)


def fitting_kernel(runtime, real) -> tuple:
    """(spectral_blocks as it fits the device, whether it spills, its work-group size): each
    work-group's windows in local memory, or, where the device has too little of it (the
    OpenCL minimum of 32 KB; NVIDIA's 48 KB per kernel in double), in global scratch memory
    (SPECTRAL_SPILL; the same arithmetic). Refused, before any work, where neither fits."""
    problem = None
    group, vector = work_shape(runtime)
    if np.dtype(real) == np.float64 and vector > 1:
        # (PoCL's LLVM 14 never built double8 on an AMD EPYC; docs/portability.md)
        vector = 1
    for spill in (0, 1):
        defines = {"SPECTRAL_GROUP": group, "SPECTRAL_VW": vector}
        if spill:
            defines["SPECTRAL_SPILL"] = 1
        kernel = runtime.kernel("inpainting/spectral.cl", "spectral_blocks", real, **defines)
        problem = runtime.group_problem(kernel, group)
        if problem is None:
            return kernel, bool(spill), group
    raise DeviceLimitError(
        f"spectral inpainting cannot run on this device: {problem}; choose another device "
        "(clpde devices) or another method (method='transport')"
    )


@register("spectral", SpectralOptions, margin=lambda omega, o: MARGIN(omega, o.block, o.border))
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    block=SpectralOptions.block,
    min_block=SpectralOptions.min_block,
    border=SpectralOptions.border,
    split=SpectralOptions.split,
    rho=SpectralOptions.rho,
    delta=SpectralOptions.delta,
    gamma=SpectralOptions.gamma,
    alpha=SpectralOptions.alpha,
    iterations=SpectralOptions.iterations,
    stop=SpectralOptions.stop,
    floor=SpectralOptions.floor,
    colour=SpectralOptions.colour,
    detrend=SpectralOptions.detrend,
    shifts=SpectralOptions.shifts,
    cutoff=SpectralOptions.cutoff,
    per_pixel=SpectralOptions.per_pixel,
    thin_border=SpectralOptions.thin_border,
    minor=SpectralOptions.minor,
    stall=SpectralOptions.stall,
):
    """Registry entry point: frequency-selective inpainting (see the module docstring).

    Options: block (largest block, even), min_block (smallest, block halved), border (the
    window's reach beyond its block; block + 2 border <= 32), split (a block whose window holds
    less known than this share is cut in four), rho (weight decay per pixel of distance), delta
    (weight of pixels filled earlier), gamma (share of each pick's coefficient taken), alpha
    (the low-frequency prior's power), iterations (most picks per block), stop (end a block once
    a pick lowers the error less than this share of the first one), floor (end a block's channel
    once its window's weighted residual RMS is at most this, data in [0, 1]), colour ('pca':
    decorrelated channels, 'channels': as given), detrend (fit a plane to each window first and
    model the rest), shifts (1, 2 or 4 block grids, offset by half a block, whose fills are
    averaged), cutoff (the candidate frequencies: |k| at most this share of the Nyquist
    frequency; 1.5 takes all), per_pixel (> 0: a block's picks are at most this many per hole
    pixel in it, at least 4), thin_border (> 0: the border where no damaged pixel lies farther
    than THIN = 4 px from a known one), minor (share of the picks that the channels after the
    first take: the principal axes of smaller variance), stall (end a block's channel once the best
    pick would lower its window's weighted squared residual by less than this share of it).
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
        floor=floor,
        colour=colour,
        detrend=detrend,
        shifts=shifts,
        cutoff=cutoff,
        per_pixel=per_pixel,
        thin_border=thin_border,
        minor=minor,
        stall=stall,
    )
