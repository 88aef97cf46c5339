"""Finding film damage: blotches (dirt, dust) and line scratches, as masks.

Films (T >= 2): each frame is compared with its motion-compensated neighbours, up to
`radius` frames each side (kernels/film/detect.cl):

- blotches: a pixel that lies outside the range of all its neighbours' values, with at
  least one neighbour on each side valid (a blotch disagrees with both sides, an occlusion
  or a revealed region with one side only), in noise units that grow with the neighbours'
  disagreement among themselves (motion the flow does not follow). Flicker is taken out
  by a per-neighbour gain and offset; the noise (grain) level is a robust estimate from
  the temporal residual. Hysteresis keeps weak pixels joined to strong ones. A candidate
  region that reappears displaced in the previous or next frame (block matching within
  `search` pixels) is a moving object, not dirt, and is dropped. A region that passes
  every check grows into its own inside and soft rim (clpde.film._grow).
- line scratches: thin, near-vertical, long lines in the temporal residual (the frame
  minus the median of its compensated neighbours), so that scene structure that moves
  with the camera (poles, door frames, text) cancels: the line response of
  clpde.film.lines, kept where a vertical run is long and most of its rows show the line.
  Scratches that stay in place (a static shot) leave no residual: the frames' own thin,
  long lines that persist over neighbouring frames are added (clpde.film.lines).

Single images (T = 1, a scanned photograph) use spatial cues only: specks that stand out
from their neighbourhood at several scales (white and black morphological top-hats on
discs of radius 1, 2, 4 and 8, compact components that step off their surroundings), and
scratches from the same line detector run on the image minus its horizontal median.
"""

from __future__ import annotations

import functools

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike
from scipy import integrate, ndimage, optimize, special

from .._progress import Progress, progress_bar
from ..errors import InputError
from ..imagedata import growth
from ..runtime import get_runtime
from ._grow import HYSTERESIS_LOW, REGION_LOW, _regions_found, grow_blotches
from ._morph import dilate
from ._motion import FilmMotion, map_frames, map_stacked
from ._order import median, second_least
from ._own_lines import residual_runs
from ._photo import photo_damage
from ._planes import film_planes, grey
from ._reflow import look_again
from ._regions import (
    RESIDUAL_UNITS,
    _local_noise_check,
    _motion_check,
    _ring_check,
    _spatial_blotches,
    _tail_check,
)
from ._tilt import at_border, leaning
from ._whole import whole_blotches
from .lines import LineKernels, film_scratches, robust_scale

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/detect.cl",)

CLEAN, BLOTCH, SCRATCH = 0, 1, 2

# Defaults chosen on the calibration sequences of benchmarks/film.py (see docs/film.md).
BLOTCH_THRESHOLD = 7.0  # noise units of the blotch score (films): benchmarks/film_calibrate.py
SCRATCH_THRESHOLD = 3.0  # robust noise units of the line response
PHOTO_SPECK_THRESHOLD = 12.0  # noise units of the top-hats (single images)
GAMMA = 2.0  # how much the neighbours' disagreement raises the blotch scale (calibrated)
CANDIDATE_THRESHOLD = 3.0  # spatial line candidates kept out of the flows
REGION_HALF = 2  # the region evidence's square: 5x5
# The smallest blotch: SMALLEST pixels, and CELLS of the grain's correlation areas (measured
# per frame, film_scores): a region of a pixel or two, or smaller than the grain's clumps, is
# a clump of grain, of the codec or of a flow error as often as damage (CELLS chosen on the
# calibration half: benchmarks/film_calibrate.py; 3 cells drop 3x3 blotches of an H.264 film,
# whose codec noise correlates over 7-16 px).
SMALLEST = 3
CELLS = 1.0
# The noise floor, 1.5 grey levels: 8-bit footage without grain (a codec's flat areas) has a
# residual whose median deviation is 0, and a level or two of quantisation is not damage.
SIGMA_FLOOR = 1.5 / 255
TRUST = 2.0  # noise units a flow inconsistency may move a compensated value
# The neighbours' range that the grain alone explains: its quantile for K trusted neighbours
# of one noise level (the range of K Gaussian samples); beyond it the spread counts as motion
# the flow does not follow. 0.99: one pixel in a hundred of a well compensated frame.
SPREAD_QUANTILE = 0.99
_SQRT_2PI = np.sqrt(2 * np.pi)


@functools.cache
def range_quantile(k: int, q: float = SPREAD_QUANTILE) -> float:
    """The q-quantile of the range of k independent standard normal samples (0 for k < 2):
    P(range <= r) = k * integral of phi(x) (Phi(x + r) - Phi(x))^(k-1) dx."""
    if k < 2:
        return 0.0

    # the standard normal's pdf and cdf spelled as scipy.stats computes them (the same
    # values): quad calls f some 200 times per root step, and each stats.norm call costs
    # ~0.1 ms of argument checks (4.6 s once per process for k <= 4)
    def pdf(x):
        return np.exp(-(x**2) / 2.0) / _SQRT_2PI

    def cdf(r: float) -> float:
        def f(x):
            return pdf(x) * (special.ndtr(x + r) - special.ndtr(x)) ** (k - 1)

        return k * integrate.quad(f, -10, 10)[0]

    return float(optimize.brentq(lambda r: cdf(r) - q, 1e-6, 20.0))


def spread_allowance(n_ok: np.ndarray, sigma: float) -> np.ndarray:
    """Per pixel, the trusted neighbours' range the grain explains (range_quantile of their
    count, in grey: each neighbour carries its own grain of level sigma)."""
    table = np.array([range_quantile(k) for k in range(int(n_ok.max(initial=0)) + 1)])
    return (table[n_ok] * sigma).astype(np.float32)


class _Kernels(LineKernels):
    """The line kernels and the blotch detector's own."""

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.blotch = rt.kernel("film/detect.cl", "detect_blotch_score")
        self.box = rt.kernel("film/detect.cl", "detect_box_mean")


def _window(t: int, T: int, radius: int) -> tuple[list[int], list[int]]:
    """Neighbour offsets of frame t and their sides. At the film's ends, where one side is
    missing, the nearer and farther neighbours of the other side stand for the two sides,
    so a blotch must still disagree with two frames that agree with each other."""
    offs = [k for k in range(-radius, radius + 1) if k != 0 and 0 <= t + k < T]
    sides = [-1 if k < 0 else 1 for k in offs]
    if len(set(sides)) == 1 and len(offs) >= 2:
        near = sorted(offs, key=abs)
        half = max(1, len(near) // 2)
        sides = [-1 if k in near[:half] else 1 for k in offs]
    return offs, sides


def _box(a: np.ndarray, half: int) -> np.ndarray:
    return ndimage.uniform_filter(a.astype(np.float32), 2 * half + 1, mode="nearest")


def _partner(k: int, offs: list[int]) -> int:
    """The neighbour whose flow loop checks neighbour k's: the same distance on the other
    side, else the nearest on the other side, else (a film's end) the other one on k's side."""
    other = [o for o in offs if (o > 0) != (k > 0)]
    if other:
        return min(other, key=lambda o: (abs(abs(o) - abs(k)), abs(o)))
    same = [o for o in offs if o != k]
    return min(same, key=abs) if same else k


def frame_scores(motion: FilmMotion, t: int, radius: int, fixed: dict | None = None) -> dict:
    """Frame t's evidence against its compensated neighbours (numpy; see the module text).

    d: how far the pixel lies outside the range of all trusted neighbours (signed), where
        a trusted neighbour exists on each side (at the film's ends: the two sides of
        _window); 0 elsewhere: an occluded, revealed or badly compensated pixel is never
        called a blotch. spread: the trusted neighbours' range, n: their count
        (blotch_evidence divides d by sigma + GAMMA * (spread beyond what the grain
        explains for n neighbours)).
    zr: the region evidence of faint blotches (5x5 means of each side's residual).
    res: the frame minus the median of its trusted neighbours; least: the scratch residual;
    trusted_both: where both sides have a trusted neighbour. fixed: the grain's level
    `sigma` and the region evidence's scale `zr_scale` measured before on the whole frame
    (a window of it scored again: clpde.film._reflow)."""
    G = motion.G
    T, ny, nx = G.shape
    offs, sides = _window(t, T, radius)
    near = sorted(offs, key=lambda k: (abs(k), k))[:2]
    nbs = [motion.neighbour(t, k) for k in offs]
    vals = np.stack([n.grey for n in nbs])
    v = G[t]
    # the grain's level from the residual against the neighbours inside the frame (robust:
    # damage and flow failures are a minority)
    inside = np.stack([motion.inside(t, t + k) for k in offs])
    med0 = median(vals, inside)
    r0 = (v - med0)[inside.any(0)]
    sigma = max(robust_scale(r0) / RESIDUAL_UNITS if r0.size else 0.0, SIGMA_FLOOR)
    if fixed is not None:
        sigma = fixed["sigma"]
    # at a film's ends all neighbours lie on one side: an occluded pixel could find two
    # that agree with each other, so the flow back must agree too
    one_sided = all(o > 0 for o in offs) or all(o < 0 for o in offs)
    ok = np.stack(
        [motion.trusted(t, k, _partner(k, offs), TRUST * sigma, fb=one_sided) for k in offs]
    )
    side = np.asarray(sides)[:, None, None]
    v = G[t]
    inf = np.float32(np.inf)
    lo = np.where(ok, vals, inf).min(0)
    hi = np.where(ok, vals, -inf).max(0)
    both = (ok & (side < 0)).any(0) & (ok & (side > 0)).any(0)
    n_ok = ok.sum(0)
    med = median(vals, ok)
    # each side's median over its own neighbours' planes (the others' would sort as +inf)
    before, after = ([i for i, sd in enumerate(sides) if sd == one] for one in (-1, 1))
    med_p = median(vals[before], ok[before])
    med_n = median(vals[after], ok[after])
    res = np.where(n_ok > 0, v - med, 0.0).astype(np.float32)
    d = np.where(v > hi, v - hi, np.where(v < lo, v - lo, 0.0))
    spread = np.where(n_ok > 0, hi - lo, 0.0)
    # where the motion is not trusted on both sides: the distance outside the range of all
    # the neighbours' compensated values, trusted or not (_spatial_blotches)
    any_in = inside.any(0)
    lo_a = np.where(inside, vals, inf).min(0)
    hi_a = np.where(inside, vals, -inf).max(0)
    d_any = np.where(any_in, np.where(v > hi_a, v - hi_a, np.where(v < lo_a, v - lo_a, 0.0)), 0.0)
    rp = np.where(np.isfinite(med_p), v - med_p, 0.0)
    rn = np.where(np.isfinite(med_n), v - med_n, 0.0)
    med = np.where(np.isfinite(med), med, v)
    bp, bn = _box(rp, REGION_HALF), _box(rn, REGION_HALF)
    same = (np.sign(bp) == np.sign(bn)) & (bp != 0) & both
    zr_scale = max(robust_scale(bp), SIGMA_FLOOR) if fixed is None else fixed["zr_scale"]
    zr = np.where(same, np.sign(bp) * np.minimum(np.abs(bp), np.abs(bn)), 0.0) / zr_scale
    # the residual's level and its grain's correlation area (pixels), measured on the frame:
    # a region of n pixels has a mean residual whose deviation is level * sqrt(area / n)
    # (footage without grain, its residual's level at the floor, has no grain to correlate:
    # what correlates there is the codec's blocks and the flow's errors; one pixel)
    raw = robust_scale(res[both]) if both.any() else 0.0
    level = max(raw, SIGMA_FLOOR)
    area = (
        25.0 * (robust_scale(_box(res, REGION_HALF)[both]) / raw) ** 2 if raw > SIGMA_FLOOR else 1.0
    )
    return {
        "region_noise": (level, max(area, 1.0)),
        "d": np.where(both, d, 0.0).astype(np.float32),
        "d_any": d_any.astype(np.float32),
        "any_in": any_in,
        "spread": spread.astype(np.float32),
        "zr": zr.astype(np.float32),
        "res": res,
        "least": second_least(v, vals, ok),
        "sigma": sigma,
        "zr_scale": zr_scale,
        "both": both,
        "n": n_ok.astype(np.int8),
        # the flows to the nearest neighbour each side: the ring check reads their spread
        "flows": np.stack([motion.flow(t, t + k) for k in (-1, 1) if 0 <= t + k < T]),
        # and the flow between the two nearest neighbours (at a film's end, both on its one
        # side), which carry none of frame t's damage
        "bridge": motion.flow(t + near[0], t + near[1]) if len(near) == 2 else None,
    }


def film_scores(G: np.ndarray, device, radius: int) -> dict:
    """The per-pixel evidence of every frame: blotch scores zb, region scores zr, line
    scores with their continuity zc, temporal residuals, noise levels and where both sides
    are trusted (the thresholds come after, in film_kinds)."""
    T, ny, nx = G.shape
    kern = LineKernels(get_runtime(device))
    motion = FilmMotion(G, keep=True)  # the next window re-reads its context's flows
    keys = ("d", "d_any", "any_in", "spread", "zr", "res", "least", "both", "n")
    stack, per = map_stacked(lambda t: frame_scores(motion, t, radius), range(T), keys)
    stack["flows"] = [p["flows"] for p in per]
    stack["bridge"] = [p["bridge"] for p in per]
    stack["region_noise"] = [p["region_noise"] for p in per]
    stack["zr_scale"] = [p["zr_scale"] for p in per]
    sigmas = np.array([p["sigma"] for p in per])
    q = kern.rt.queue
    zs = np.stack(
        [
            kern.line_score(cla.to_device(q, np.ascontiguousarray(stack["least"][t])), 3 * s)
            for t, s in enumerate(sigmas)
        ]
    )
    # the motion stays for a second look at the frames' blotches (clpde.film._reflow)
    out = {**stack, "zc": kern.continuity(zs), "sigma": sigmas, "radius": radius}
    return {**out, "motion": motion}


def _no_singletons(mask: np.ndarray, smallest: float = 2) -> np.ndarray:
    labels, n = ndimage.label(mask)
    if n == 0:
        return mask
    sizes = np.bincount(labels.ravel())
    keep = sizes >= smallest
    keep[0] = False
    return keep[labels]


def blotch_evidence(
    scores: dict, t: int, gamma: float, low: float
) -> tuple[np.ndarray, np.ndarray]:
    """Frame t's blotch evidence per pixel (film_scores' evidence), in noise units that grow
    with the neighbours' disagreement among themselves beyond what the grain explains
    (pathological motion: the flow does not follow the scene there): the pixel's own
    score, or its region's where the pixel owns it; and that region evidence alone (0 where
    not owned). A pixel owns its square's region score where its own residual shows the
    same sign beyond the noise and either reaches the `low` level (noise units) by itself
    or carries at least half the square's mean residual (the nearer of the two: the
    region's shift or none): beside a blotch, a pixel of grain or of the flow's halo around
    it has the blotch in its square but not in itself, and a strong blotch's region score
    does not spill past its edge."""
    sigma, r = scores["sigma"][t], scores["res"][t]
    allowed = spread_allowance(scores["n"][t], sigma)
    scale = sigma + gamma * np.maximum(scores["spread"][t] - allowed, 0.0)
    zb = scores["d"][t] / scale
    zr = scores["zr"][t] * (sigma / scale)
    own = (np.sign(r) == np.sign(zr)) & (np.abs(r) > 1.5 * sigma)
    own &= (np.abs(r) >= low * sigma) | (np.abs(r) >= 0.5 * np.abs(_box(r, REGION_HALF)))
    zr = np.where(own, np.abs(zr), 0.0).astype(np.float32)
    return np.maximum(np.abs(zb), zr), zr


def _untrusted(
    G: np.ndarray,
    scores: dict,
    t: int,
    blotch: np.ndarray,
    scratch: np.ndarray,
    threshold: float,
    smallest: float,
    search: int,
) -> np.ndarray:
    """Frame t's blotches where a trusted neighbour is missing on one side (the motion is
    not trusted there, or a film's end), found spatially and against all the neighbours'
    compensated values (clpde.film._regions._spatial_blotches), then the tail check on
    that distance; the fill takes them spatially (no two trusted candidates agree there)."""
    sigma, d_any = scores["sigma"][t], scores["d_any"][t]
    z = np.where(scores["both"][t], 0.0, np.abs(d_any) / sigma)
    taken = dilate(blotch | scratch)
    low = HYSTERESIS_LOW * threshold
    sign = np.sign(d_any)
    found = _spatial_blotches(G, t, z, sign, threshold, low, smallest, sigma, search, taken)
    busy = dilate(found | taken, 2)
    area = scores["region_noise"][t][1]
    return _tail_check(found, busy, d_any, area, scores["any_in"][t])


def _frame_kinds(
    G: np.ndarray,
    scores: dict,
    t: int,
    still: np.ndarray,
    blotch_threshold: float,
    scratch_threshold: float,
    search: int,
    min_length: int,
    gamma: float,
) -> np.ndarray:
    """Frame t's kinds (H, W) from film_scores' evidence (film_kinds, one frame)."""
    res, sigmas = scores["res"], scores["sigma"]
    # the residual's line runs; near a film's end, those that are a neighbour's ghost apart
    runs, ghosts = residual_runs(G, scores, t, scratch_threshold, min_length)
    scratch = runs | still
    low = HYSTERESIS_LOW * blotch_threshold
    (a, zr), r = blotch_evidence(scores, t, gamma, low), res[t]
    fragments = (a > low) | (zr > REGION_LOW * blotch_threshold)
    blotch, a = _regions_found(a, zr, r, scores["region_noise"][t], blotch_threshold)
    blotch &= ~dilate(scratch | ghosts)
    # a lone pixel, or a clump of a few, is within what a codec or the grain does: never a
    # blotch worth a fill
    smallest = max(SMALLEST, CELLS * scores["region_noise"][t][1])
    blotch = _no_singletons(blotch, smallest)
    flows = (scores["flows"][t], scores["bridge"][t])
    blotch = _ring_check(blotch, scores["both"][t], r, sigmas[t], *flows)
    blotch = _local_noise_check(blotch, a, r, sigmas[t], blotch_threshold)
    # the surroundings' tail is read outside all candidates and their rims
    busy = dilate(blotch | scratch, 2)
    blotch = _tail_check(blotch, busy, r, scores["region_noise"][t][1], scores["both"][t])
    blotch = _motion_check(blotch, G, t, res[t], search, sigmas[t], blotch_threshold)
    taken = scratch | ghosts
    blotch = grow_blotches(blotch, taken, scores["d"][t], r, scores["n"][t] > 0, sigmas[t], low)
    blotch |= _untrusted(G, scores, t, blotch, taken, blotch_threshold, smallest, search)
    # two witnesses at the low level: where both sides are trusted, a region whose temporal
    # evidence reaches only the low level is damage where the frame's own surroundings say so
    # at that level too and it is not found again nearby (the spatial test of _untrusted)
    weak = np.where(scores["both"][t], a, 0.0)
    busy = dilate(blotch | taken)
    blotch |= _spatial_blotches(G, t, weak, np.sign(r), low, low, smallest, sigmas[t], search, busy)
    if "motion" in scores and blotch.any():
        # a second look around the blotches, with flows their damage does not drag
        def evidence(sc: dict) -> np.ndarray:
            return blotch_evidence(sc, t, gamma, low)[0]

        blotch = look_again(scores, t, blotch, taken, evidence, blotch_threshold, frame_scores)
    if "motion" in scores and 0 < t < G.shape[0] - 1:
        # whole faint blotches whose fragments the first pass dropped (clpde.film._whole)
        motion, offs = scores["motion"], _window(t, G.shape[0], scores["radius"])[0]

        def neighbours() -> list:
            return [
                (motion.warped(t, t + k), motion.inside(t, t + k), motion.gain(t, t + k)[0])
                for k in offs
            ]

        found = blotch | taken
        args = (fragments, found, smallest, blotch_threshold, search, neighbours)
        blotch |= whole_blotches(G, scores, t, *args)
    # a tall thin "blotch" is a scratch the line detector missed (too short or faint
    # for its run test in this frame)
    labels, _ = ndimage.label(blotch)
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        h = sl[0].stop - sl[0].start
        if h >= 0.5 * min_length and (labels[sl] == idx).sum() <= 4 * h:
            scratch[sl] |= labels[sl] == idx
            blotch[sl] &= labels[sl] != idx
    # a long thin line leaning off the vertical is neither, a line at the frame's left or
    # right border no scratch (clpde.film._tilt)
    blotch &= ~leaning(blotch)
    scratch &= ~(leaning(scratch) | at_border(scratch))
    kinds = np.zeros(G.shape[1:], np.int8)
    kinds[blotch] = BLOTCH
    kinds[scratch] = SCRATCH
    return kinds


def film_kinds(
    G: np.ndarray,
    scores: dict,
    blotch_threshold: float,
    scratch_threshold: float,
    search: int,
    min_length: int,
    gamma: float = GAMMA,
) -> np.ndarray:
    """Kinds (T, H, W) from film_scores' evidence and the thresholds."""
    T, ny, nx = G.shape
    # scratches that stay in place (static shots, slow zooms) leave no temporal residual:
    # the frames' own thin lines that persist over neighbouring frames
    still = film_scratches(
        G, scratch_threshold, min_length, scores["sigma"], scores["flows"], scores["radius"]
    )

    def kinds_of(t: int) -> np.ndarray:
        return _frame_kinds(
            G, scores, t, still[t], blotch_threshold, scratch_threshold, search, min_length, gamma
        )

    kinds = np.stack(map_frames(kinds_of, range(T)))
    # a film's first and last frames see one side only: a scratch there must continue (within
    # two columns) in the next frame in, which sees both sides
    if T >= 3:
        wide = np.ones((1, 5), bool)
        for end, inner in ((0, 1), (T - 1, T - 2)):
            lone = (kinds[end] == SCRATCH) & ~dilate(kinds[inner] == SCRATCH, structure=wide)
            kinds[end][lone] = CLEAN
    return kinds


def _grow_kinds(kinds: np.ndarray, px: float) -> np.ndarray:
    if px <= 0:
        return kinds
    out = kinds.copy()
    for t in range(kinds.shape[0]):
        hit = kinds[t] > 0
        if not hit.any():
            continue
        dist, (iy, ix) = ndimage.distance_transform_edt(~hit, return_indices=True)
        ring = (dist <= px) & ~hit
        out[t][ring] = kinds[t][iy[ring], ix[ring]]
    return out


def detect_defects(
    frames: ArrayLike,
    *,
    channel_axis: int | None = None,
    blotch_threshold: float | None = None,
    scratch_threshold: float | None = None,
    grow: float = 0,
    radius: int = 2,
    search: int = 24,
    min_length: int | None = None,
    return_kinds: bool = False,
    device: str | int | None = None,
    progress: Progress = None,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Find blotches (dirt, dust) and line scratches in film frames or a scanned photo.

    For a film (two frames or more) every frame is compared with its motion-compensated
    neighbours, `radius` frames each side (optical flow on the device): a blotch is a
    region that disagrees with the neighbours on both sides while they agree with each
    other, after a per-frame flicker correction, in units of the grain's level; regions
    that reappear displaced in the next or previous frame (objects the flow missed) are
    not blotches. A line scratch is a thin, near-vertical, long line in the frame minus
    its compensated neighbours (scene lines moving with the camera cancel there), kept when
    it is long and continues over consecutive frames. A scratch that moves exactly with
    the scene (a static shot) cannot be told from scene structure this way.
    A single image (2-D, or colour with channel_axis) uses spatial cues only: compact specks
    that stand out at several scales (morphological top-hats) and long thin vertical lines.

    Parameters
    ----------
    frames : array, (T, H, W) or (T, H, W, C); or one image (H, W) or (H, W, C)
        Integer or float frames, never modified; colour is averaged to grey.
    channel_axis : int, optional
        The channel axis of colour frames (e.g. -1).
    blotch_threshold : float, optional
        The blotch sensitivity: the score, in noise units, a blotch must reach somewhere
        (its region grows to half of it). Lower finds fainter dirt and more false alarms.
        Default 6 for films, 12 for single images (the top-hat score).
    scratch_threshold : float, optional
        The scratch sensitivity, in robust noise units of the line response (default 3).
    grow : float
        Grow the found damage by a disc of this radius in pixels (0: as found); grown
        pixels take the kind of the nearest damaged pixel.
    radius : int
        Neighbour frames each side that a frame is compared with (at least 2 recommended;
        the film's ends use the frames on their one side).
    search : int
        How far, in pixels, a candidate region is searched for in the previous and next
        frames to tell a moving object from a blotch.
    min_length : int, optional
        The shortest scratch in rows (default: 40% of the frame height, at least 24).
    return_kinds : bool
        Also return the kind of each pixel.
    device : str or int, optional
        As for `clpde.diffuse`.
    progress : bool or callable, optional
        As for `clpde.inpaint`: a bar over the detection's two stages (the temporal scores,
        then the kinds), or a callable ``progress(done, total)`` that may stop the run by
        raising.

    Returns
    -------
    mask : bool ndarray (T, H, W), or (H, W) for one 2-D or colour image
        True where damaged.
    kinds : int8 ndarray of the same shape, with return_kinds
        0 clean, 1 blotch, 2 line scratch.

    Raises
    ------
    InputError
        Frames of a shape or dtype clpde cannot use, or a bad parameter.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> rng = np.random.default_rng(0)
    >>> from scipy.ndimage import gaussian_filter
    >>> scene = gaussian_filter(rng.random((64, 96)), 2)
    >>> frames = np.stack([scene[:, t:t + 64] for t in range(5)])  # a pan
    >>> frames[2, 30:36, 30:36] = 0.0  # a dark blotch on the middle frame
    >>> mask = clpde.detect_defects(frames)
    >>> bool(mask[2, 30:36, 30:36].all()), int(mask[[0, 1, 3, 4]].sum())
    (True, 0)
    """
    planes, layout = film_planes(frames, channel_axis)
    G = grey(planes)
    T, ny, nx = G.shape
    px = growth(grow)
    for name, val in (("radius", radius), ("search", search)):
        if not isinstance(val, (int, np.integer)) or val < 1:
            raise InputError(f"{name} must be a positive integer, not {val!r}")
    for name, val in (
        ("blotch_threshold", blotch_threshold),
        ("scratch_threshold", scratch_threshold),
    ):
        if val is not None and not (np.isfinite(val) and val > 0):
            raise InputError(f"{name} must be a positive number, not {val!r}")
    if min_length is None:
        min_length = max(24, int(0.4 * ny))
    elif not isinstance(min_length, (int, np.integer)) or min_length < 1:
        raise InputError(f"min_length must be a positive integer, not {min_length!r}")
    sthr = SCRATCH_THRESHOLD if scratch_threshold is None else float(scratch_threshold)
    if T == 1:
        bthr = PHOTO_SPECK_THRESHOLD if blotch_threshold is None else float(blotch_threshold)
        specks, scratch = photo_damage(G[0], bthr, sthr, int(min_length), device)
        kinds = np.zeros((1, *G.shape[1:]), np.int8)
        kinds[0][specks & ~scratch] = BLOTCH
        kinds[0][scratch] = SCRATCH
    else:
        bthr = BLOTCH_THRESHOLD if blotch_threshold is None else float(blotch_threshold)
        with progress_bar(progress, 2, "clpde detect_defects", unit="stage") as bar:
            scores = film_scores(G, device, int(radius))
            bar.update(1)
            kinds = film_kinds(G, scores, bthr, sthr, int(search), int(min_length))
            bar.update(1)
    kinds = _grow_kinds(kinds, px)
    if layout.photo:
        kinds = kinds[0]
    mask = kinds > 0
    return (mask, kinds) if return_kinds else mask


__all__ = ["BLOTCH", "CLEAN", "SCRATCH", "detect_defects"]
