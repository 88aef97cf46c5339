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
  `search` pixels) is a moving object, not dirt, and is dropped.
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

from dataclasses import replace

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike
from scipy import ndimage, signal
from skimage.morphology import black_tophat, disk, white_tophat

from .._progress import Progress, progress_bar
from ..errors import InputError
from ..imagedata import growth
from ..runtime import get_runtime
from ._compensate import FILM_FLOW, Compensator
from ._frames import film_planes, grey
from .lines import LineKernels, robust_scale, scratch_runs, spatial_lines, static_scratches

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/detect.cl",)

CLEAN, BLOTCH, SCRATCH = 0, 1, 2

# The first pass's flows: cheaper, their errors only decide what the second pass masks.
FIRST_PASS_FLOW = replace(FILM_FLOW, iterations=10)

# Defaults chosen on the calibration sequences of benchmarks/film.py (see docs/film.md).
BLOTCH_THRESHOLD = 6.0  # noise units of the blotch score (films)
SCRATCH_THRESHOLD = 3.0  # robust noise units of the line response
PHOTO_SPECK_THRESHOLD = 12.0  # noise units of the top-hats (single images)
GAMMA = 0.5  # how much the neighbours' own disagreement raises the blotch scale
CANDIDATE_THRESHOLD = 3.0  # spatial line candidates kept out of the flows
FIRST_PASS_LEVEL = 2.0  # blotch score of the first pass masked out of the second's flows
MATCH_RATIO = 0.25  # a displaced match this much better than the compensated one: motion
REGION_HALF = 2  # the region evidence's square: 5x5
HYSTERESIS_LOW = 0.5  # share of the blotch threshold a region grows into
STATIC_SCALE = 0.5  # the static-line detector's threshold per unit of scratch_threshold


def _hysteresis(a: np.ndarray, low: float, high: float) -> np.ndarray:
    """The connected regions of a > low that reach a > high somewhere."""
    labels, n = ndimage.label(a > low)
    strong = np.zeros(n + 1, bool)
    strong[np.unique(labels[a > high])] = True
    strong[0] = False
    return strong[labels]


class _Kernels(LineKernels):
    """The line kernels and the blotch detector's own."""

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.blotch = rt.kernel("film/detect.cl", "blotch_score")
        self.box = rt.kernel("film/detect.cl", "box_mean")


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


def _masked_ssd(win: np.ndarray, templ: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Sum over the template of weight * (window - template)^2 at every placement that fits
    (the 'valid' placements, top-left corners), by three correlations."""
    w = win.astype(np.float64)
    tpl = templ.astype(np.float64)
    flip = (slice(None, None, -1), slice(None, None, -1))
    a = signal.fftconvolve(w * w, weight[flip], mode="valid")
    b = signal.fftconvolve(w, (weight * tpl)[flip], mode="valid")
    return a - 2.0 * b + float((weight * tpl * tpl).sum())


def _motion_check(
    comp_mask: np.ndarray, G: np.ndarray, t: int, resid: np.ndarray, search: int
) -> np.ndarray:
    """Drop the components of comp_mask (frame t) that reappear displaced in the frames
    before and after: a moving object the flow missed is found again nearby, a blotch is
    not.

    Each component, with a ring of two pixels for context, is matched within `search`
    pixels of its place in each neighbour. It moved if, at the best places, its own pixels
    differ by less than MATCH_RATIO of their difference from the compensated neighbours
    (medians of squares),
    in both neighbours, at places that one velocity explains (steady motion; chance
    matches of a blotch do not line up so). The film's first and last frames use the next
    two frames on their one side; a film of two frames needs the match of the ring too."""
    labels, n = ndimage.label(comp_mask)
    if n == 0:
        return comp_mask
    T, ny, nx = G.shape
    keep = np.ones(n + 1, bool)
    keep[0] = False
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        y0, y1 = max(sl[0].start - 3, 0), min(sl[0].stop + 3, ny)
        x0, x1 = max(sl[1].start - 3, 0), min(sl[1].stop + 3, nx)
        own = labels[y0:y1, x0:x1] == idx
        region = ndimage.binary_dilation(own, iterations=2)
        r2 = resid[y0:y1, x0:x1] ** 2
        # medians: a component may carry some clean pixels or a trail beside the object
        e_own, e_region = float(np.median(r2[own])), float(r2[region].mean())
        templ = np.ascontiguousarray(G[t, y0:y1, x0:x1])
        th, tw = templ.shape
        found = []
        # the frames each side; at the film's ends the next two on the one side
        pair = (t - 1, t + 1) if 0 < t < T - 1 else ((t + 1, t + 2) if t == 0 else (t - 1, t - 2))
        for s in pair:
            if not 0 <= s < T:
                continue
            wy0, wy1 = max(y0 - search, 0), min(y1 + search, ny)
            wx0, wx1 = max(x0 - search, 0), min(x1 + search, nx)
            win = np.ascontiguousarray(G[s, wy0:wy1, wx0:wx1])
            if win.shape[0] < th or win.shape[1] < tw:
                continue
            res = _masked_ssd(win, templ, region.astype(np.float64))
            my, mx = np.unravel_index(int(np.argmin(res)), res.shape)
            diff = (templ - win[my : my + th, mx : mx + tw]) ** 2
            found.append(
                (
                    float(np.median(diff[own])),
                    float(diff[region].mean()),
                    np.array([my + wy0 - y0, mx + wx0 - x0], float) / (s - t),
                )
            )
        if not found or not all(f[0] < MATCH_RATIO * e_own for f in found):
            continue
        if len(found) == 2:
            # one velocity explains both places (displacements per frame of offset)
            (_, _, v0), (_, _, v1) = found
            moved = np.hypot(*(v0 - v1)) <= 3.0 and np.hypot(*v0) >= 1.0
        else:
            moved = found[0][1] < 2 * MATCH_RATIO * e_region
        keep[idx] = not moved
    return keep[labels]


def _blotch_pass(comp: Compensator, kern: _Kernels, T: int, radius: int, line_of=None):
    """Blotch scores, temporal residuals and noise levels of every frame against its
    compensated neighbours; with line_of, also each frame's line score (its continuity
    comes after)."""
    ny, nx = comp.ny, comp.nx
    q = comp.q
    g, loc = comp.rt.items(nx, ny)
    zb = np.empty((T, ny, nx), np.float32)
    res = np.empty((T, ny, nx), np.float32)
    zs = np.empty((T, ny, nx), np.float32) if line_of else None
    least = np.empty((T, ny, nx), np.float32)
    sigmas = np.empty(T)
    z_dev = cla.empty(q, (ny, nx), np.float32)
    r_dev = cla.empty(q, (ny, nx), np.float32)
    m_dev = cla.empty(q, (ny, nx), np.float32)
    sides_dev = [cla.empty(q, (ny, nx), np.float32) for _ in range(4)]
    zr = np.empty((T, ny, nx), np.float32)
    for t in range(T):
        offs, sides = _window(t, T, radius)
        nb = comp.neighbours(t, offs, sides)
        args = (
            comp.grey[t].data,
            nb.grey.data,
            nb.valid.data,
            cla.to_device(q, nb.gain).data,
            cla.to_device(q, nb.offset).data,
            cla.to_device(q, nb.side).data,
            np.int32(len(offs)),
        )
        kern.blotch(
            q,
            g,
            loc,
            *args,
            np.float32(1.0),
            np.float32(GAMMA),
            z_dev.data,
            r_dev.data,
            m_dev.data,
            sides_dev[0].data,
            sides_dev[1].data,
            np.int32(nx),
            np.int32(ny),
        )
        r = r_dev.get()
        # the residual against the median of ~4 neighbours has about 1.16 times the
        # frame's own noise deviation; a floor keeps noiseless synthetic frames sane
        sigma = max(robust_scale(r) / 1.16, 0.5 / 255)
        kern.blotch(
            q,
            g,
            loc,
            *args,
            np.float32(sigma),
            np.float32(GAMMA),
            z_dev.data,
            r_dev.data,
            m_dev.data,
            sides_dev[0].data,
            sides_dev[1].data,
            np.int32(nx),
            np.int32(ny),
        )
        zb[t], res[t], least[t], sigmas[t] = z_dev.get(), r, m_dev.get(), sigma
        # region evidence: each side's residual averaged over 5x5, both of one sign, in the
        # robust units of that average (which knows the grain's own correlation)
        for src, dst in zip(sides_dev[:2], sides_dev[2:], strict=True):
            kern.box(
                q, g, loc, src.data, dst.data, np.int32(REGION_HALF), np.int32(nx), np.int32(ny)
            )
        bp, bn = sides_dev[2].get(), sides_dev[3].get()
        same = (np.sign(bp) == np.sign(bn)) & (bp != 0)
        zr[t] = np.where(same, np.sign(bp) * np.minimum(np.abs(bp), np.abs(bn)), 0.0) / (
            robust_scale(bp)
        )
        if line_of:
            zs[t] = kern.line_score(m_dev, 3.0 * sigma)
    return zb, res, least, sigmas, zs, zr


def film_scores(G: np.ndarray, device, radius: int) -> dict:
    """The per-pixel evidence of every frame: blotch scores zb, line scores with their
    continuity zc, temporal residuals, noise levels and the frames' own signed thin lines
    (the thresholds come after, in film_kinds)."""
    T, ny, nx = G.shape
    kern = _Kernels(get_runtime(device))
    # Thin vertical lines of the frames themselves (scene lines and scratches alike) are
    # kept out of the flows: a scratch fixed on the film would otherwise pull the flow
    # around it to zero, and the compensated neighbours would show it too.
    lines = np.zeros((T, ny, nx), np.int8)
    for t in range(T):
        lines[t] = spatial_lines(kern, G[t], CANDIDATE_THRESHOLD, max(12, ny // 5))
    near_line = np.stack(
        [ndimage.binary_dilation(x != 0, structure=np.ones((1, 5), bool)) for x in lines]
    )
    # A first, cheaper pass finds what stands out; the flows are then estimated again with
    # it masked out, since a large blotch drags the flow around it even with a robust data
    # term, and the neighbours warped by that flow disagree where they should agree.
    comp = Compensator(G, device, weights=1.0 - near_line, params=FIRST_PASS_FLOW)
    zb = _blotch_pass(comp, kern, T, radius)[0]
    suspect = np.stack(
        [
            ndimage.binary_dilation(_hysteresis(np.abs(z), FIRST_PASS_LEVEL, 2 * FIRST_PASS_LEVEL))
            for z in zb
        ]
    )
    # Each neighbour's own suspects are left out where they land: a neighbour's own blotch
    # would otherwise pass for disagreement among the neighbours.
    wide = np.stack([ndimage.binary_dilation(x) for x in suspect])
    comp = Compensator(G, device, weights=1.0 - (near_line | wide), exclude=suspect)
    zb, res, least, sigmas, zs, zr = _blotch_pass(comp, kern, T, radius, line_of=True)
    return {
        "zb": zb,
        "zr": zr,
        "zc": kern.continuity(zs),
        "res": res,
        "least": least,
        "sigma": sigmas,
        "lines": lines,
    }


def film_kinds(
    G: np.ndarray,
    scores: dict,
    blotch_threshold: float,
    scratch_threshold: float,
    search: int,
    min_length: int,
) -> np.ndarray:
    """Kinds (T, H, W) from film_scores' evidence and the thresholds."""
    T, ny, nx = G.shape
    zb, zc, res, sigmas = scores["zb"], scores["zc"], scores["res"], scores["sigma"]
    kinds = np.zeros((T, ny, nx), np.int8)
    # scratches that stay in place (static shots, slow zooms) leave no temporal residual:
    # the frames' own thin lines that persist over neighbouring frames
    still = (
        static_scratches(G, STATIC_SCALE * scratch_threshold, min_length)
        if STATIC_SCALE > 0
        else np.zeros((T, ny, nx), bool)
    )
    for t in range(T):
        scratch = (
            scratch_runs(zc[t], scores["least"][t], sigmas[t], scratch_threshold, min_length)
            | still[t]
        )
        # a pixel's evidence: its own score, or its region's where its own residual shows
        # the same sign beyond the noise (so a strong blotch's region score does not spill
        # past its edge)
        zr, r = scores["zr"][t], res[t]
        own = (np.sign(r) == np.sign(zr)) & (np.abs(r) > 1.5 * sigmas[t])
        a = np.maximum(np.abs(zb[t]), np.where(own, np.abs(zr), 0.0))
        blotch = _hysteresis(a, HYSTERESIS_LOW * blotch_threshold, blotch_threshold)
        blotch &= ~ndimage.binary_dilation(scratch)
        blotch = _motion_check(blotch, G, t, res[t], search)
        # a tall thin "blotch" is a scratch the line detector missed (too short or faint
        # for its run test in this frame)
        labels, _ = ndimage.label(blotch)
        for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
            h = sl[0].stop - sl[0].start
            if h >= 0.5 * min_length and (labels[sl] == idx).sum() <= 4 * h:
                scratch[sl] |= labels[sl] == idx
                blotch[sl] &= labels[sl] != idx
        kinds[t][blotch] = BLOTCH
        kinds[t][scratch] = SCRATCH
    return kinds


def _photo(
    G: np.ndarray, speck_threshold: float, scratch_threshold: float, min_length: int, device
) -> np.ndarray:
    ny, nx = G.shape
    # the grain's level from the image minus its 5x5 median: film grain is correlated over
    # a pixel or two, which the finest-scale estimate of denoising misses
    sigma = max(robust_scale(G - ndimage.median_filter(G, size=5, mode="nearest")), 0.5 / 255)
    specks = np.zeros((ny, nx), bool)
    for rad in (1, 2, 4, 8):
        # at each scale, the components that stand out and fit in its disc: a speck, not
        # a stroke, an edge or a broad bump
        white = white_tophat(G, footprint=disk(rad))
        black = black_tophat(G, footprint=disk(rad))
        found = np.maximum(white, black) > speck_threshold * sigma
        labels, n = ndimage.label(found)
        keep = np.zeros(n + 1, bool)
        for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
            h, w = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
            area = int((labels[sl] == idx).sum())
            if not (
                max(h, w) <= 2 * rad + 1 and max(h, w) <= 3 * min(h, w) + 1 and area >= 0.3 * h * w
            ):
                continue
            # a speck steps off its surroundings; a smooth bump fades into them
            comp = labels == idx
            ring = ndimage.binary_dilation(comp, iterations=2) & ~comp
            step = abs(float(G[comp].mean()) - float(np.median(G[ring])))
            keep[idx] = step > speck_threshold * sigma
        specks |= keep[labels]
    resid = G - ndimage.median_filter(G, size=(1, 9), mode="nearest")
    rt = get_runtime(device)
    kern = LineKernels(rt)
    zs = kern.line_score(
        cla.to_device(rt.queue, np.ascontiguousarray(resid, np.float32)), 3.0 * sigma
    )
    scratch = scratch_runs(zs, resid, sigma, scratch_threshold, min_length, thin=False)
    kinds = np.zeros((ny, nx), np.int8)
    kinds[specks & ~scratch] = BLOTCH
    kinds[scratch] = SCRATCH
    return kinds[np.newaxis]


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
        kinds = _photo(G[0], bthr, sthr, int(min_length), device)
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
