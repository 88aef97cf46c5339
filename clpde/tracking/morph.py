"""The morphing of one frame pair on the device: the coupled system (2.3)-(2.6) of the thesis,

    F1_t = beta |grad F1|,   u_t = beta (N_F1 . N_u) |grad u|,   beta = F2 - F1,

stepped over the band of a `LevelSet` until the contour stops moving or a cap of iterations,
with the band rebuilt whenever the front nears its edge. beta is F2 - F1, the steepest
ascent of a local normalised cross-correlation or a Huber-clipped difference
(kernels/tracking/features.cl), or the adaptive blend of the correlation and the difference
with a region and a curvature term (kernels/tracking/adaptive.cl).
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from ..fields import Field, PingPong
from .levelset import CFL, NEAR_EDGE, LevelSet
from .options import DISCREPANCIES, TrackOptions
from .region_term import REGION_REFRESH, RegionTerm

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/features.cl", "tracking/adaptive.cl")

# The adaptive discrepancy's weights, chosen on the calibration half of
# benchmarks/track_corpus.py (benchmarks/tracking_generalise.py --calibrate for the adaptive
# option, benchmarks/track_default_search.py for the default, which also keeps the
# correlation's hold under a shadow and a flicker: docs/tracking.md).
CONTRAST_NOISE = 4.0  # the correlation takes over where a window's variance passes this x noise
DISCREPANCY_WEIGHT = 1.0  # the frame-to-frame discrepancy's share of the contour's speed


def morph_kernel_name(ls: LevelSet, discrepancy: str) -> str:
    """The morphing step's kernel for the band's storage (tracking/storage.py: with bricks
    walked by one work-item, the NCC's is features_morph_track_tiled)."""
    return ls.store.morph_kernel(discrepancy)


def _step_kernel(
    ls: LevelSet,
    options: TrackOptions,
    channels: int,
    region: RegionTerm | None,
    noise2: float,
):
    """The step's kernel and the arguments that follow the common ones (the adaptive
    step's region field, noise threshold and weights)."""
    g = ls.grid
    if options.discrepancy != "adaptive":
        kernel = ls.band_kernel(
            "tracking/features.cl",
            morph_kernel_name(ls, options.discrepancy),
            NCH=channels,
            DISC=DISCREPANCIES[options.discrepancy],
            WIN=options.ncc_radius,
        )
        return kernel, ()
    terms = options.region_weight > 0 or options.curvature > 0 or options.appearance_weight > 0
    kernel = ls.band_kernel(
        "tracking/adaptive.cl",
        ls.store.KERNELS["adaptive"],
        NCH=channels,
        WIN=options.ncc_radius,
        FRONT_ONLY=int(terms),
    )
    extra = (
        (region.field if region is not None else ls.u.cur).data.data,
        g.scalar(CONTRAST_NOISE * noise2 + 1e-6),
        g.scalar(options.curvature),
        g.scalar(DISCREPANCY_WEIGHT),
    )
    return kernel, extra


def _largest_dt(options: TrackOptions) -> float:
    """The cap of the adaptive time step: F1's relaxation towards F2 must not overshoot,
    nor u's towards the prior (dt lam <= 1/2), nor the explicit curvature term."""
    lam = options.shape_weight
    max_dt = max(options.max_dt, options.dt)
    dt_cap = max_dt if lam == 0 else min(max_dt, 0.5 / lam)
    if options.discrepancy == "adaptive" and options.curvature > 0:
        dt_cap = min(dt_cap, 0.2 / options.curvature)  # the explicit curvature term's limit
    return dt_cap


def morph_pair(
    ls: LevelSet,
    f1: Field,
    f2: Field,
    prior: Field,
    options: TrackOptions,
    channels: int,
    region: RegionTerm | None = None,
    noise2: float = 0.0,
) -> tuple[int, bool, float]:
    """Run the coupled system on one frame pair; returns (iterations, converged, final
    mean |beta| in the band).

    The time step adapts at each check to the largest stable one: the level sets move at
    most CFL pixels per step (dt (|beta| + lam w) <= CFL), F1's relaxation towards F2 does
    not overshoot (dt |grad F1| <= 1) nor does u's towards the prior (dt lam <= 1/2). It
    restarts from `options.dt` whenever the band changes. A region term with a weight is
    updated every REGION_REFRESH iterations, following the contour as Chan-Vese's
    statistics do.
    """
    g = ls.grid
    kernel, extra = _step_kernel(ls, options, channels, region, noise2)
    pair = PingPong(f1)
    lam = options.shape_weight
    delta = options.huber_delta if options.discrepancy == "huber" else 0.02
    consts = (
        g.scalar(0.02**2),
        g.scalar(1e-3**2),
        g.scalar(NEAR_EDGE),
        g.scalar(lam),
        g.scalar(delta),
        np.int32(g.sx),
        np.int32(g.plane),
    )
    dt_cap = _largest_dt(options)
    first_dt = min(options.dt, dt_cap)
    stats = None
    dt = first_dt
    converged = False
    iterations = 0
    residual = 0.0
    while iterations < options.iterations:
        if ls.band.n == 0:  # the contour vanished from the frame
            converged = True
            break
        refresh = iterations and iterations % REGION_REFRESH == 0
        if refresh and region is not None and region.follows:
            region.update(ls)  # the statistics follow the contour, as Chan-Vese's do
        if stats is None:
            parts = ls.band_parts()
            stats = cla.zeros(g.runtime.queue, 5 * parts + 1, g.dtype)
        ls.launch_band(
            kernel,
            ls.band,
            ls.u.cur.data.data,
            pair.cur.data.data,
            f2.data.data,
            ls.band_mask.data,
            prior.data.data,
            ls.u.nxt.data.data,
            pair.nxt.data.data,
            stats.data,
            g.scalar(dt),
            *consts,
            *extra,
        )
        ls.u.swap()
        pair.swap()
        iterations += 1
        if iterations % options.check_every == 0 or iterations == options.iterations:
            # One small read every few steps: speed, stability maxima and edge flag.
            values = stats.get()
            fastest, beta_max, grad_max = (
                values[k * parts : (k + 1) * parts].max() for k in range(3)
            )
            residual = float(
                values[3 * parts : 4 * parts].sum() / max(values[4 * parts : 5 * parts].sum(), 1)
            )
            if fastest < options.tol:
                converged = True
                break
            if values[5 * parts]:
                ls.rebuild(options.reinit_iterations)
                pair.nxt.assign(pair.cur)  # the band moved: both copies agree outside it
                stats = None
                dt = first_dt
            else:
                speed = beta_max + lam * options.band_width
                dt = float(min(dt_cap, CFL / max(speed, 1e-6), 1.0 / max(grad_max, 1e-6)))
    return iterations, converged, residual
