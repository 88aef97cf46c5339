"""Filling film damage from the neighbouring frames, with spatial inpainting where they fail.

Per damaged frame: optical flow to each neighbour up to `radius` frames away, estimated with
the damage of both frames masked out; each neighbour warped onto the frame, its flicker
corrected by a gain and offset fitted on the clean pixels; every damaged pixel copies the
value of one neighbour that sees it clean, chosen by how well each neighbour matches the
frame around the pixel and then as the medoid of the remaining candidates
(kernels/film/fill.cl). Copying one real frame's value keeps its grain. Pixels no neighbour
sees clean (a scratch at the same place in every neighbour, a region revealed by motion)
are filled by `clpde.inpaint`, with grain of the frame's measured level added so that
they do not show as smooth patches.
"""

from __future__ import annotations

import zlib

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from .._progress import Progress, progress_bar
from ..errors import InputError
from ..imagedata import noise_std
from ..inpainting.api import inpaint
from ..motion.dis import to_u8
from ._compensate import fit_gain
from ._morph import dilate
from ._motion import FilmMotion, map_frames
from ._planes import film_masks, film_planes, grey
from ._regions import RIM_CLEAR
from ._scratch_fill import mend_scratches, run_ends
from .detect import BLOTCH, SCRATCH, SIGMA_FLOOR, _partner
from .lines import LINE_COVER

# A neighbour's warped place counts as clean below this degree of damage (the bilinear
# warp of a bool mask spreads it over a pixel's rim).
_CLEAN = 0.01
# The half width of the window on which neighbours are compared with the frame.
_RADIUS_MATCH = 4
# The wider window a pixel deep inside a hole is matched on where the 9x9 one holds no clean
# pixel: a blotch up to ~11 px in radius has its surround within 12 px of every pixel (before
# filmfill such pixels had no candidate at all and fell back to the spatial fill).
_RADIUS_WIDE = 12
# noise units within which a neighbour matches the frame around the pixel (a mean absolute
# difference; of two frames' grain alone it is ~1.1 sigma; warp blur adds to it): chosen on
# the calibration half, 3 -> 4.5 raised the damaged pixels' PSNR by 0.9 dB, 6 by no more
AGREE = 4.5
PAIR = 3.0  # noise units within which two candidates agree on the pixel
TRUST = 2.0  # noise units a flow inconsistency may move a compensated value
CROP_MARGIN = 16  # pixels of context around the holes the spatial fill is given


def _spatial(frame: np.ndarray, hole: np.ndarray, options: dict) -> np.ndarray:
    """clpde.inpaint on one (C, H, W) [0, 1] frame."""
    image = frame[0] if frame.shape[0] == 1 else np.moveaxis(frame, 0, -1)
    axis = None if frame.shape[0] == 1 else -1
    out = inpaint(image.astype(np.float32), hole, channel_axis=axis, **options)
    out = np.asarray(out, np.float32)
    # inpaint scales a float image by its own range and returns that range: keep [0, 1]
    return out[np.newaxis] if axis is None else np.moveaxis(out, -1, 0)


def _spatial_crops(frame: np.ndarray, hole: np.ndarray, options: dict) -> np.ndarray:
    """_spatial on crops around the holes (holes closer than 2 * CROP_MARGIN share one), so
    a few small holes do not cost a whole frame's inpainting; the crops' margins give the
    fill its context. Outside the holes the frame is returned as it was."""
    out = frame.copy()
    ny, nx = hole.shape
    groups, _ = ndimage.label(dilate(hole, CROP_MARGIN))
    for sl in ndimage.find_objects(groups):
        y0, y1 = max(sl[0].start, 0), min(sl[0].stop, ny)
        x0, x1 = max(sl[1].start, 0), min(sl[1].stop, nx)
        box = (slice(None), slice(y0, y1), slice(x0, x1))
        if min(y1 - y0, x1 - x0) < 8:  # too small for clpde.inpaint: the whole frame
            return np.where(hole[None], _spatial(frame, hole, options), frame)
        h = hole[y0:y1, x0:x1]
        out[box] = np.where(h[None], _spatial(frame[box], h, options), frame[box])
    return out


def _neighbour_mean(planes: np.ndarray, m: np.ndarray, t: int, radius: int) -> np.ndarray:
    """A frame marked damaged everywhere (dropped, burnt) whose neighbours the motion could
    not align: the per-pixel mean of the neighbours within `radius` that are clean there,
    the nearest first; a blurred stand-in is better than the damage, and none other exists."""
    T = len(planes)
    for r in range(1, radius + 1):
        near = [u for u in range(t - r, t + r + 1) if u != t and 0 <= u < T]
        clean = np.stack([m[u] == 0 for u in near])[:, None]
        if clean.any(axis=0).all():
            total = np.where(clean, planes[near], 0.0).sum(axis=0)
            return (total / clean.sum(axis=0)).astype(planes.dtype)
    raise InputError(
        f"frame {t} is marked damaged everywhere and its neighbours within {radius} frames "
        "are damaged too, so nothing is left to fill it from; check the masks or raise radius"
    )


def _rough(G: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The grey frames with their damage filled roughly (OpenCV's Telea), for the flows
    only: DIS cannot be told to ignore pixels, and a blotch would drag the flow around it."""
    import cv2

    out = G.copy()

    def one(t: int) -> None:  # the frames in threads: each writes its own plane
        hole = m[t] > 0
        if hole.any():
            u8 = to_u8(G[t])
            out[t] = cv2.inpaint(u8, hole.astype(np.uint8), 3, cv2.INPAINT_TELEA) / np.float32(255)

    map_frames(one, range(len(G)))
    return out


class _FarMotion(FilmMotion):
    """FilmMotion whose flows between frames 3 or 4 apart (the far neighbours', and the near
    ones' loop check across frame t) are composed of DIS's flows of 1 and 2 frames, the
    second carried along the first: 3 = 2 + 1, 4 = 1 + 3 (= 1 + 2 + 1). DIS would cost 2-4
    more flows per frame (the fill's flows were most of its time); on the calibration clips
    the composed flows fill as well (damaged px 24.84 against DIS's 24.95 dB, 4 neighbours
    each side). The path of 4 = 1 + 2 + 1 skips its middle frame: the near neighbours' loop
    t + 2 -> t - 2 never reads frame t, as before (its own damage does not decide it)."""

    def _estimate(self, t: int, s: int) -> np.ndarray:
        d = s - t
        if abs(d) <= 2:
            return super()._estimate(t, s)
        mid = t + int(np.sign(d)) * (2 if abs(d) == 3 else 1)
        return self.flow(t, mid) + self.warp(self.flow(mid, s), t, mid, "linear")


def _temporal(
    motion: FilmMotion,
    planes: np.ndarray,
    hwc: np.ndarray,
    m: np.ndarray,
    t: int,
    radius: int,
    noise: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frame t's damaged pixels from its neighbours where the motion is trusted; returns the
    frame (C, H, W), the pixels left to the spatial fill, and the squared residual of the
    frame against its candidates (below; the smallest; inf where there is none): what the
    data says the damage changed (`_self_check`). hwc: the planes as (T, H, W, C), the
    layout the warp reads; noise: frame t's grain level (noise_std).

    A neighbour is a candidate at a pixel where its match is trusted (clpde.film._motion:
    inside, the flow loop consistent within the noise), clean in its own mask, and it agrees
    with frame t on the clean pixels of the 9x9 window around (mean absolute difference
    within AGREE noise units and 1.5 times the best). A pixel is filled only where at least
    two candidates agree with each other (within PAIR noise units): one neighbour alone
    could carry damage nobody found, and it would be copied in. Then the medoid's value is
    copied, every channel from the same frame (its grain comes along); ties go to the
    nearer frame, then the earlier."""
    G = motion.G
    T, C, ny, nx = planes.shape
    hole = m[t] > 0
    offs = [k for k in range(-radius, radius + 1) if k != 0 and 0 <= t + k < T]
    sigma = max(noise, SIGMA_FLOOR)
    one_sided = all(o > 0 for o in offs) or all(o < 0 for o in offs)
    near = [o for o in offs if abs(o) <= 2]
    # The fit and the agreement windows read the whole frame; the choice among the
    # candidates only the damaged pixels: from here on, vectors over those (the same
    # values as whole planes: every step is per pixel).
    vals, cols, cand, dist = [], [], [], []
    ctx_t = ~dilate(hole)  # grow_mask(hole, 1.0): the disc of radius 1 is the cross
    for k in offs:
        s = t + k
        clean = motion.warp(m[s], t, s, "linear") <= _CLEAN
        ok = clean & motion.trusted(t, k, _loop_partner(k, near), TRUST * sigma, fb=one_sided)
        w = motion.warped(t, s)  # kept by trusted
        a, b = fit_gain(G[t], w, ok & ctx_t)
        wg = a * w + b
        ctx = (ok & ctx_t).astype(np.float32)
        e = _match(np.abs(G[t] - wg) * ctx, ctx, hole)
        vals.append(wg[hole])
        cols.append(a * motion.warp_at(hwc[s], t, s, hole) + b)  # (n, C)
        cand.append(ok[hole] & (e <= AGREE * sigma))
        dist.append(abs(k) + (0.5 if k > 0 else 0.0))
    vals, cand = np.stack(vals), np.stack(cand)  # (K, n)
    resid2 = np.full((ny, nx), np.inf, np.float32)
    # E^2 from the candidates only (their window agrees with the frame's own): a trusted
    # neighbour that disagrees around the pixel is misaligned there, and its difference
    # from the frame is the motion's error, not damage (filmharm2: on tree d's fast motion
    # such neighbours passed false alarms' repairs)
    resid2[hole] = np.where(cand, (G[t][hole][None] - vals) ** 2, np.inf).min(0)
    e_ok = cand
    # agreement among the candidates: the medoid's cost, and how many agree with it
    K, n = vals.shape
    cost = np.full((K, n), np.inf, np.float32)
    agree = np.zeros((K, n), np.int16)
    for i in range(K):
        diff = np.abs(vals[i][None] - vals)
        c = np.where(e_ok, diff, 0.0).sum(0) + 1e-6 * dist[i]
        cost[i] = np.where(e_ok[i], c, np.inf)
        agree[i] = (e_ok & (diff <= PAIR * sigma)).sum(0)
    best = np.argmin(cost, axis=0)
    n_agree = agree[best, np.arange(n)]
    filled_at = np.isfinite(cost.min(0)) & (n_agree >= 2)
    chosen = np.stack(cols)[best, np.arange(n)]  # (n, C)
    soft = m[t][hole][:, None]
    blend = soft * chosen + (1 - soft) * planes[t][:, hole].T
    out = planes[t].copy()
    out[:, hole] = np.where(filled_at[None], blend.T, out[:, hole])
    filled = np.zeros((ny, nx), bool)
    filled[hole] = filled_at
    return out.astype(np.float32), hole & ~filled, resid2


def _loop_partner(k: int, near: list[int]) -> int:
    """The neighbour whose flow loop checks neighbour k's: within 2 frames the detector's
    (`_partner`, the same distance on the other side); a farther one loops through the frame
    2 nearer on its own side, so its check reads a flow of 2 frames, which the near
    neighbours' checks estimate anyway (the same distance on the other side would need flows
    of 6 and 8 frames: 4 more flows per frame instead of 2)."""
    return _partner(k, near) if abs(k) <= 2 else k - 2 * int(np.sign(k))


def _match(diff: np.ndarray, ctx: np.ndarray, hole: np.ndarray) -> np.ndarray:
    """The mean of diff over the clean context ctx (float 0/1) around each pixel of hole, in
    the 9x9 window, else the 25x25 one (a pixel deep inside a large hole), else inf. The
    windows are summed on the holes' bounding box only (with the window's margin): the
    values are the whole frame's (the filter's border is the frame's, and the box reaches
    it wherever the window does)."""
    ys, xs = np.nonzero(hole)
    ny, nx = hole.shape
    pad = _RADIUS_WIDE + 1
    y0, y1 = max(ys.min() - pad, 0), min(ys.max() + pad + 1, ny)
    x0, x1 = max(xs.min() - pad, 0), min(xs.max() + pad + 1, nx)
    box = (slice(y0, y1), slice(x0, x1))
    d, c, h = diff[box], ctx[box], hole[box]
    e = np.full(len(ys), np.inf, np.float32)
    for r in (_RADIUS_MATCH, _RADIUS_WIDE):
        num = ndimage.uniform_filter(d, 2 * r + 1)[h]
        den = ndimage.uniform_filter(c, 2 * r + 1)[h]
        e = np.where(np.isfinite(e), e, np.where(den > 1e-3, num / np.maximum(den, 1e-6), np.inf))
    return e


def line_evidence(frame: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """The squared deviation of a frame's detected line scratches against their flanks:
    the spatial counterpart of the temporal residual, for a line whose
    neighbours carry it too (so that no clean neighbour shows what it covers).

    Per row, each run of line pixels is compared with its flanks, the mean of the two
    columns 2-3 px beyond either end of the run; the line's sign is its region's median
    deviation from the flanks' mean, and its deviation is each pixel's beyond the *worse*
    flank in that sign (as the detector's line contrast, clpde.film.lines: an edge, or a
    pixel between two flanks, shows no line), 0 where the pixel does not pass it; and 0
    over the whole line unless in at least LINE_COVER of its rows the run passes its
    worse flank on average (as the detector asks of a line's rows): a line's profile keeps
    its sign along it, texture's and an edge's do not.

    Parameters
    ----------
    frame : numpy.ndarray
        One grey frame (H, W), float.
    lines : numpy.ndarray
        Bool (H, W): the line scratches' pixels.

    Returns
    -------
    numpy.ndarray
        float32 (H, W): the squared deviation on `lines`, 0 elsewhere.

    Examples
    --------
    >>> g = np.full((6, 12), 0.5, np.float32); g[:, 5:7] = 0.3  # a dark line, 2 px wide
    >>> lines = np.zeros(g.shape, bool); lines[:, 5:7] = True
    >>> bool(np.allclose(line_evidence(g, lines)[lines], 0.04))
    True
    """
    ny, nx = frame.shape
    out = np.zeros((ny, nx), np.float32)
    if not lines.any():
        return out
    # each line pixel's run: its first and last columns in the row
    first, last = run_ends(lines)

    # from here on, vectors over the line pixels only (in the frame's order): every step
    # is per pixel or per labelled region, so the values are the whole frame's
    ys, xs = np.nonzero(lines)
    f = frame[ys, xs]

    def at(cols: np.ndarray) -> np.ndarray:
        return frame[ys, np.clip(cols, 0, nx - 1)]

    firsts, lasts = first[ys, xs], last[ys, xs]
    left = 0.5 * (at(firsts - 3) + at(firsts - 2))
    right = 0.5 * (at(lasts + 2) + at(lasts + 3))
    labels, n = ndimage.label(lines)
    labels = labels[ys, xs]
    index = np.arange(1, n + 1)
    dev = f - 0.5 * (left + right)
    s = np.sign(np.concatenate([[0.0], ndimage.median(dev, labels, index)]))[labels]
    e = s * f - np.maximum(s * left, s * right)
    # a line shows in most of its rows (the detector's LINE_COVER): a row's run passes
    # its worse flank on average; texture does so in a few rows, an edge in none
    runs, m = ndimage.label(lines, structure=[[0, 0, 0], [1, 1, 1], [0, 0, 0]])
    runs = runs[ys, xs]
    shows = np.concatenate([[False], ndimage.mean(e, runs, np.arange(1, m + 1)) > 0])[runs]
    share = np.concatenate([[0.0], ndimage.mean(shows, labels, index)])[labels]
    e = np.where(share >= LINE_COVER, np.maximum(e, 0.0), 0.0)
    out[ys, xs] = e**2
    return out


def ring_evidence(frame: np.ndarray, spots: np.ndarray, hole: np.ndarray) -> np.ndarray:
    """The squared distance of each pixel of a frame's detected blotches outside the range
    (5th to 95th percentile) of its region's ring, 3-5 px out and off the damage: the
    spatial counterpart of the temporal residual where no neighbour is trusted, as the
    detector's spatial test (clpde.film._regions._spatially_damage).

    Parameters
    ----------
    frame : numpy.ndarray
        One grey frame (H, W), float.
    spots : numpy.ndarray
        Bool (H, W): the blotches' pixels.
    hole : numpy.ndarray
        Bool (H, W): all the frame's damage (left out of the rings).

    Returns
    -------
    numpy.ndarray
        float32 (H, W): the squared distance on `spots`, 0 elsewhere.

    Examples
    --------
    >>> g = np.full((20, 20), 0.5, np.float32); g[8:12, 8:12] = 0.2  # a dark blotch
    >>> spots = g < 0.3
    >>> bool(np.allclose(ring_evidence(g, spots, spots)[spots], 0.09))
    True
    """
    out = np.zeros(frame.shape, np.float32)
    labels, _ = ndimage.label(spots)
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        win = tuple(slice(max(s.start - RIM_CLEAR[1], 0), s.stop + RIM_CLEAR[1]) for s in sl)
        own = labels[win] == idx
        # the detector's ring: nearer in, a soft rim blends the dirt into the scene
        ring = dilate(own, RIM_CLEAR[1])
        ring &= ~dilate(own, RIM_CLEAR[0]) & ~hole[win]
        if ring.sum() < 4:
            continue
        g = frame[win]
        lo, hi = np.percentile(g[ring], [5, 95])
        e = np.maximum(np.maximum(lo - g, g - hi), 0.0)
        out[win][own] = (e**2)[own]
    return out


def _self_check(
    restored: np.ndarray,
    frame: np.ndarray,
    hole: np.ndarray,
    resid2: np.ndarray,
    sigma: float,
    lines: np.ndarray | None = None,
    spots: np.ndarray | None = None,
    spatial: np.ndarray | None = None,
) -> np.ndarray:
    """The regions of `hole` whose repair the data does not explain: where the mean squared
    change D^2 of the repair (grey) exceeds twice the mean squared residual E^2 of the frame
    against its compensated neighbours.

    Derived from the noise, not fitted: on damage of amplitude d repaired right, D = -d plus
    the repair's grain minus the frame's, E = d plus the frame's grain minus a neighbour's,
    so both have the mean square d^2 + 2 sigma^2; on a pixel that was not damaged E^2 is
    the 2 sigma^2 of two grainy values alone. So a repair may change a region by what the
    residual shows plus as much again for the noise of a ratio of two means (E^2 >= 2
    sigma^2: a region's mean E^2 is never below one noise pair); a region without a trusted
    neighbour is granted the noise alone (E^2 = 2 sigma^2: no evidence of damage but the
    detector's). Without a trusted clean neighbour, the detection's own spatial evidence
    stands in: on a line scratch (`lines`; its neighbours carry it, flagged) the line's
    deviation beyond its flanks (`line_evidence`, which on a line also stands beside the
    temporal residual: the larger of the two counts, since a neighbour may carry the
    scratch unflagged), on a blotch (`spots`; the motion not
    trusted) its distance outside its ring's range (`ring_evidence`): there the temporal
    residual says nothing, and the noise alone would refuse every such repair. A false
    alarm shows no such deviation (the frame before a scratch begins, texture), and keeps
    its values. With `spatial` (the pixels the spatial fill took), each region's spatially
    and temporally filled parts are tested apart: a spatial repair the ring does not
    explain does not ride on its region's temporal residual. Returns the bool (H, W)
    pixels whose repair is refused."""
    labels, n = ndimage.label(hole)
    if n == 0:
        return np.zeros(hole.shape, bool)
    if spatial is not None:  # each region's spatially filled part apart (filmharm2)
        labels = np.where(spatial & hole, labels + n, labels)
    # the regions' means read their own pixels only: vectors over the hole's pixels
    where = np.nonzero(hole)
    floor = np.full(len(where[0]), 2 * sigma**2, np.float32)
    if lines is not None and lines.any():
        floor = np.where(lines[where], line_evidence(frame, lines)[where], floor)
    if spots is not None and spots.any():
        floor = np.where(spots[where], ring_evidence(frame, spots, hole)[where], floor)
    e2 = resid2[where]
    e2 = np.where(np.isfinite(e2), e2, floor)
    if lines is not None and lines.any():
        # on a line scratch either witness explains the repair: a neighbour that carries
        # the scratch unflagged (the detector missed it there) is a candidate whose
        # residual says "nothing changed", while the line's deviation beyond its flanks
        # still shows it (filmbudget: on calibration such refusals cost 6% of detect +
        # fill's squared error); a false alarm without a line in the frame shows no
        # deviation, and the temporal residual still speaks for it
        e2 = np.where(lines[where], np.maximum(e2, floor), e2)
    d2 = (restored[where] - frame[where]) ** 2
    # the ratio of the means is that of the sums (a part with no pixels sums to 0: kept)
    sum_d2 = np.bincount(labels[where], d2, minlength=2 * n + 1)
    sum_e2 = np.bincount(labels[where], e2, minlength=2 * n + 1)
    return (sum_d2 > 2 * sum_e2)[labels]


def inpaint_video(
    frames: ArrayLike,
    masks: ArrayLike,
    *,
    channel_axis: int | None = None,
    radius: int = 4,
    grain: bool = True,
    seed: int = 0,
    spatial: dict | None = None,
    device: str | int | None = None,
    keep: float = 0.0,
    kinds: ArrayLike | None = None,
    return_unfilled: bool = False,
    progress: Progress = None,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Fill damaged pixels of film frames from the neighbouring frames that see them clean.

    For each frame with damage, dense optical flow to each neighbour up to `radius` frames
    away is estimated on the device with the damage masked out; each damaged pixel copies
    the flicker-corrected value of the neighbour that best agrees with the frame around it
    (the medoid of the agreeing candidates), all channels from the same frame, so the grain
    stays. Where no neighbour sees a pixel clean, `clpde.inpaint`'s default fills it, with
    grain of the frame's measured level added (``grain=True``). Neighbours are read as
    given, never as already filled, so each frame's result depends only on its window.

    Parameters
    ----------
    frames : array, (T, H, W) or (T, H, W, C)
        Integer or float frames, never modified. One image (H, W) (or (H, W, C) with
        channel_axis) is filled spatially.
    masks : array, (T, H, W)
        The damage per frame: bool, nonzero integers, or floats in [0, 1] (soft: the output
        blends fill and frame by the degree of damage), as in `clpde.inpaint`.
    channel_axis : int, optional
        The channel axis of colour frames (e.g. -1).
    radius : int
        Neighbour frames each side to fill from. 4 (2 before filmfill): on the calibration
        clips with the true masks, 2 -> 4 raised the damaged pixels' PSNR by 1.65 dB.
    grain : bool
        Add grain of the measured level where the spatial fill had to be used.
    seed : int
        Seed of that grain, so runs repeat exactly.
    spatial : dict, optional
        Keyword arguments for `clpde.inpaint` where the neighbours do not help.
    device : str or int, optional
        As for `clpde.diffuse`.
    keep : float
        Pixels whose fill lies within `keep` noise deviations (the frame's grain level) of
        their own value keep their own value: with detected masks, a pixel the fill would
        barely change was most likely not damaged (do no harm). And on a film, each region
        of the mask whose repair changes it more than its residual against the trusted
        neighbours explains (mean squares, D^2 > 2 E^2) keeps its own values. 0: fill every
        masked pixel. `clpde restore` uses 3.
    kinds : array, (T, H, W), optional
        The defect kinds of detected masks (clpde.detect_defects' return_kinds: 1 blotch,
        2 line scratch). With `keep`, where no trusted neighbour sees a pixel clean, the
        residual E^2 of a scratch is its deviation beyond its flanks, and of a blotch its
        distance outside its ring's range, instead of the noise alone: a scratch that
        every neighbour carries is repaired. None: every region as a blotch without such
        evidence (given masks).
    return_unfilled : bool
        Also return the bool (T, H, W) mask of the pixels the spatial fill took.
    progress : bool or callable, optional
        As for `clpde.inpaint`: a bar over the frames, or a callable
        ``progress(done, total)`` that may stop the run by raising.

    Returns
    -------
    ndarray
        The restored frames, the input's shape and dtype; with return_unfilled, also the
        pixels no neighbour filled.

    Raises
    ------
    InputError
        Masks of the wrong count or size, frames clpde cannot use, a bad parameter.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> from scipy.ndimage import gaussian_filter
    >>> scene = gaussian_filter(np.random.default_rng(0).random((64, 96)), 2)
    >>> clean = np.stack([scene[:, t:t + 64] for t in range(5)])  # a pan
    >>> dirty = clean.copy(); dirty[2, 20:30, 20:30] = 1.0
    >>> masks = np.zeros(clean.shape, bool); masks[2, 20:30, 20:30] = True
    >>> out = clpde.inpaint_video(dirty, masks)
    >>> bool(np.abs(out[2, 20:30, 20:30] - clean[2, 20:30, 20:30]).mean() < 0.005)
    True
    """
    planes, layout = film_planes(frames, channel_axis)
    T, C, ny, nx = planes.shape
    m = film_masks(masks, (T, ny, nx), layout.photo)
    if not isinstance(radius, (int, np.integer)) or radius < 1:
        raise InputError(f"radius must be a positive integer, not {radius!r}")
    options = {} if spatial is None else dict(spatial)
    if kinds is not None:
        kinds = np.asarray(kinds)
        if kinds.size != T * ny * nx:
            raise InputError(
                f"kinds are {kinds.shape}; give one kind per mask pixel, {(T, ny, nx)} "
                "(detect_defects' return_kinds)"
            )
        kinds = kinds.reshape(T, ny, nx)
    G = grey(planes)
    out = planes.copy()
    unfilled = np.zeros((T, ny, nx), bool)
    resid2 = np.full((T, ny, nx), np.inf, np.float32)
    damaged = [t for t in range(T) if m[t].any()]
    # temporal fills first, then the spatial fallback: one unit per damaged frame for each
    bar = progress_bar(progress, 2 * len(damaged), "clpde inpaint_video", unit="frame")
    # each damaged frame's grain level, read by the temporal fill, the grain and the keep
    levels = map_frames(lambda t: noise_std(G[t].astype(np.float64)), damaged)
    noise = dict(zip(damaged, levels, strict=True))
    if T > 1 and damaged:
        motion = _FarMotion(G, _rough(G, m))
        hwc = np.ascontiguousarray(np.moveaxis(planes, 1, -1))  # each frame warped 2-4 times
        # the damaged frames in threads: each reads the shared flows and the input only
        results = map_frames(
            lambda t: _temporal(motion, planes, hwc, m, t, radius, noise[t]),
            damaged,
            done=bar.update,
        )
        for t, (frame, left, r2) in zip(damaged, results, strict=True):
            out[t], unfilled[t], resid2[t] = frame, left, r2
    elif damaged:
        unfilled = m > 0

    def finish(t: int) -> np.ndarray:
        """Frame t after the spatial fallback, its grain and the keep (one frame's inputs
        and fill only: the frames run in threads)."""
        frame = out[t]
        hole = unfilled[t]
        if kinds is not None and T > 1:  # detected scratches: their profile taken out
            lines = (kinds[t] == SCRATCH) & (m[t] > 0)
            frame, hole = mend_scratches(frame, planes[t], m[t], lines, hole)
        if hole.any():
            # only the pixels no neighbour filled: the temporal fills around them are its
            # context (before filmfill the hole grew by 1 px into them, and on calibration
            # the 12% of damaged pixels so overwritten lost 4.5 dB: 27.4 -> 22.9)
            if hole.all():  # a lost frame: nothing in it to fill from spatially
                filled = _neighbour_mean(planes, m, t, radius)
            else:
                filled = _spatial_crops(frame, hole, options)
            soft = m[t][np.newaxis]
            blend = soft * filled + (1.0 - soft) * planes[t]
            if grain:
                # seeded by the frame itself, so a frame's grain is the same in any window
                rng = np.random.default_rng([seed, zlib.crc32(np.ascontiguousarray(G[t]).data)])
                blend = blend + (noise[t] * soft * rng.standard_normal((1, ny, nx))).astype(
                    np.float32
                )
            frame = np.where(hole[np.newaxis], blend, frame)
        if keep > 0:
            sigma = max(noise[t], SIGMA_FLOOR)
            restored = grey(frame[np.newaxis])[0]
            close = np.abs(restored - G[t]) <= keep * sigma
            if T > 1:
                kept = np.where(close, G[t], restored)  # the repair as it will stand
                lines = spots = None
                if kinds is not None:
                    lines, spots = kinds[t] == SCRATCH, kinds[t] == BLOTCH
                close |= _self_check(
                    kept, G[t], m[t] > 0, resid2[t], sigma, lines, spots, unfilled[t]
                )
            frame = np.where(close[None], planes[t], frame)
        return frame

    done = bar.update if T > 1 else lambda n: bar.update(2 * n)  # no temporal stage
    for t, frame in zip(damaged, map_frames(finish, damaged, done=done), strict=True):
        out[t] = frame
    bar.close()
    restored = layout.restore_changed(out, planes)
    if return_unfilled:
        return restored, (unfilled[0] if layout.photo else unfilled)
    return restored
