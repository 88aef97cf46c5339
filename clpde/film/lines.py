"""Line scratches: thin, long, near-vertical lines, found in a residual or in the frames.

Two detectors share this module.

The line response of a residual (kernels/film/detect.cl), which the temporal detector of
clpde.film.detect runs on each frame minus its compensated neighbours and a single image's
detector on the image minus its horizontal median: a column mean of the clamped residual,
a thin-line response across it in robust noise units, summed with the matching response of
the previous and next frames within a pixel of drift (`LineKernels`); then the long
vertical runs of it whose rows mostly show the line (`scratch_runs`).

Scratches that stay in place (`static_scratches`): a spatial, per-frame thin-line detector
with continuity over frames. The temporal detector sees a scratch only where the scene
moves past it; in a static shot or near the centre of a slow zoom the compensated
neighbours carry the same scratch and the residual is flat. This detector looks at each
frame itself: a vertically smoothed frame, across each column a line profile (the centre
against its flanks at LINE_FLANK pixels), kept where

- the line is thin: two pixels out from the centre the profile is already most of the way
  back to the flanks (scratches are 1-3 px wide; poles, posts and door frames are wider);
- the flanks match each other: they differ by less than the line stands off them (an edge
  or a step beside a line is scene structure);
- it stands out in robust noise units of the profile over the frame;
- it persists: at least VOTES of the up-to-four frames around it (within two frames) show
  a line of the same sign within DRIFT pixels (a scratch drifts slowly across the frame;
  scene lines in a pan of a pixel or more per frame leave that window);
- it runs long along y (the film detector's `min_length`).

A thin, isolated, long vertical line that stays in place in a static shot is, to this
detector, a scratch: the picture offers nothing else to tell them apart.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from ..imagedata import noise_std
from ._order import median_of

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/detect.cl",)

# Scratches that stay in place:
LINE_FLANK = 3  # flanks 3 pixels either side: lines up to 3-4 px wide
THIN_RATIO = 0.5  # two pixels out, the profile keeps at most this share of the centre's
DRIFT = 1  # pixels a scratch may move between the frames compared
SMOOTH_ROWS = 6.0  # Gaussian along y (rows) before the profile: grain averages out
WIDTH_SHARE = 0.4  # beside the centre, a scratch's pixels stand out by this share
VOTES = 3  # frames around it that must show the line (all of them at the film's ends)
BRIDGE_ROWS = 9  # gaps of a few rows bridged (a scratch fades in places)
# The line response of a residual (the temporal detector's, and the spatial one's):
COLUMN_HALF = 12  # rows each side of the column mean
RESPONSE_FLANK = 3  # the response's flanks at 3 and 4 pixels: lines up to 5 px wide
RUN_SUPPORT = 0.5  # share of a scratch run's rows whose residual shows the line


def robust_scale(a: np.ndarray) -> float:
    """The median absolute deviation of a's finite values, as a Gaussian's deviation."""
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float(1.4826 * np.median(a)) + 1e-9  # NaN, as ever
    return float(1.4826 * median_of(np.abs(a - median_of(a)))) + 1e-9


class LineKernels:
    """The line response's kernels on one runtime (kernels/film/detect.cl)."""

    def __init__(self, rt) -> None:
        self.rt = rt
        self.colmean = rt.kernel("film/detect.cl", "detect_column_mean")
        self.line = rt.kernel("film/detect.cl", "detect_line_response")
        self.cont = rt.kernel("film/detect.cl", "detect_scratch_continuity")

    def line_score(self, resid: cla.Array, lim: float) -> np.ndarray:
        """The thin-line response of a residual plane, in its robust noise units."""
        q = self.rt.queue
        ny, nx = resid.shape
        g, loc = self.rt.items(nx, ny)
        col = cla.empty(q, (ny, nx), np.float32)
        out = cla.empty(q, (ny, nx), np.float32)
        self.colmean(
            q,
            g,
            loc,
            resid.data,
            col.data,
            np.int32(min(COLUMN_HALF, ny // 4)),
            np.float32(lim),
            np.int32(nx),
            np.int32(ny),
        )
        self.line(
            q, g, loc, col.data, out.data, np.int32(RESPONSE_FLANK), np.int32(nx), np.int32(ny)
        )
        score = out.get()
        return score / robust_scale(score[:, RESPONSE_FLANK + 1 : nx - RESPONSE_FLANK - 1])

    def continuity(self, zs: np.ndarray) -> np.ndarray:
        """Each frame's line score summed with the previous and next frames' matching
        response within a pixel of drift (a scratch continues over frames)."""
        q = self.rt.queue
        T, ny, nx = zs.shape
        g, loc = self.rt.items(nx, ny)
        dev = [cla.to_device(q, np.ascontiguousarray(z)) for z in zs]
        out = np.empty_like(zs)
        tmp = cla.empty(q, (ny, nx), np.float32)
        for t in range(T):
            prev, nxt = dev[max(t - 1, 0)], dev[min(t + 1, T - 1)]
            self.cont(
                q,
                g,
                loc,
                prev.data,
                dev[t].data,
                nxt.data,
                np.int32(t > 0),
                np.int32(t < T - 1),
                tmp.data,
                np.int32(nx),
                np.int32(ny),
            )
            out[t] = tmp.get()
        return out


def scratch_runs(
    zc: np.ndarray,
    resid: np.ndarray,
    sigma: float,
    threshold: float,
    min_length: int,
    lines: np.ndarray | None = None,
    signed: bool = False,
    thin: bool = True,
) -> np.ndarray:
    """Long vertical runs of the line score above threshold whose rows mostly show the
    line in the residual itself, with their adjacent columns above half the threshold.

    lines, given: the frame's own signed thin lines (+1 bright, -1 dark); a run counts only
    where the frame shows a line of its sign within a pixel (a scratch is a line in the
    frame; the neighbours' scratches warped onto it leave ghost lines in the residual
    only). signed: return +1 / -1 / 0 by the line's sign instead of a bool mask. thin:
    require quiet flanks (a temporal residual is quiet beside a scratch; an image's own
    texture is not, so the spatial detectors leave it out)."""
    ny, nx = zc.shape
    out = np.zeros((ny, nx), np.int8)
    for sgn in (1.0, -1.0):
        s = sgn * zc
        hit = s > threshold
        if lines is not None:
            own = ndimage.binary_dilation(lines == sgn, structure=np.ones((1, 3), bool))
            hit &= own
        if not hit.any():
            continue
        # bridge gaps of a few rows (a scratch fades in places)
        hit = ndimage.binary_closing(hit, structure=np.ones((7, 1), bool)) | hit
        labels, n = ndimage.label(hit, structure=np.array([[0, 1, 0]] * 3, bool))
        if n == 0:
            continue
        sizes = np.bincount(labels.ravel())
        shown = sgn * resid
        shown3 = np.maximum(
            np.maximum(shown, np.roll(shown, 1, axis=1)), np.roll(shown, -1, axis=1)
        )
        support = np.bincount(labels.ravel(), weights=(shown3 > 2.0 * sigma).ravel())
        # a scratch is thin: beside it, 3 to 5 columns away on both sides, the residual is
        # quiet in most rows; an object the flow missed leaves a broad residual
        quiet = np.ones((ny, nx), bool)
        for off in (-5, -4, -3, 3, 4, 5):
            quiet &= np.abs(np.roll(resid, off, axis=1)) < 2.0 * sigma
        calm = np.bincount(labels.ravel(), weights=quiet.ravel())
        good = (sizes >= min_length) & (support >= RUN_SUPPORT * np.maximum(sizes, min_length))
        if thin:
            good &= calm >= RUN_SUPPORT * sizes
        good[0] = False
        core = good[labels]
        if not core.any():
            continue
        # the column mean carries a run past the scratch's ends and the drift match
        # beside it: keep the rows and columns whose own residual shows the line (gaps of
        # a few rows bridged, as above)
        shows = sgn * resid > sigma
        rows = ndimage.binary_closing(shows, structure=np.ones((9, 1), bool)) | shows
        wide = ndimage.binary_dilation(core, structure=np.ones((1, 3), bool))
        out[(core & rows) | (wide & (s > 0.5 * threshold) & shows)] = int(sgn)
    return out if signed else out != 0


def spatial_lines(
    kern: LineKernels, G: np.ndarray, threshold: float, min_length: int
) -> np.ndarray:
    """Thin, long, near-vertical lines of one image from spatial cues alone, signed (+1
    bright, -1 dark, 0 none): the line detector on the image minus its horizontal median."""
    sigma = max(noise_std(G.astype(np.float64)), 0.5 / 255)
    resid = G - ndimage.median_filter(G, size=(1, 9), mode="nearest")
    zs = kern.line_score(
        cla.to_device(kern.rt.queue, np.ascontiguousarray(resid, np.float32)), 3.0 * sigma
    )
    return scratch_runs(zs, resid, sigma, threshold, min_length, signed=True, thin=False)


def _shift(a: np.ndarray, dx: int) -> np.ndarray:
    """a moved by dx columns (a[:, x + dx] at x), edges repeated."""
    if dx == 0:
        return a
    idx = np.clip(np.arange(a.shape[1]) + dx, 0, a.shape[1] - 1)
    return a[:, idx]


def line_evidence(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed thin-line evidence of one frame.

    Parameters
    ----------
    frame : numpy.ndarray
        One grey frame (H, W), float.

    Returns
    -------
    z : numpy.ndarray
        (H, W) float32: the line's contrast against the worse of its two flanks, in robust
        noise units of the profile, at a line's centre (positive bright, negative dark);
        zero off a centre or where the flanks differ by more than the line stands off them.
    thin : numpy.ndarray
        (H, W) bool: where the profile is thin enough for a scratch.
    profile : numpy.ndarray
        (H, W) float32: every pixel against the mean of its flanks, in the same units.

    Examples
    --------
    >>> import numpy as np
    >>> f = np.full((40, 30), 0.5, np.float32) + 0.01 * np.random.default_rng(0).random((40, 30))
    >>> f[:, 15] = 0.1
    >>> z, thin, _ = line_evidence(f)
    >>> bool(z[20, 15] < -3 and thin[20, 15])
    True
    """
    s = ndimage.gaussian_filter1d(frame.astype(np.float32), SMOOTH_ROWS, axis=0, mode="nearest")
    left, right = _shift(s, -LINE_FLANK), _shift(s, LINE_FLANK)
    z = np.zeros_like(s)
    thin = np.zeros(s.shape, bool)
    for sgn in (1.0, -1.0):
        c = sgn * s - np.maximum(sgn * left, sgn * right)
        flank_mean = 0.5 * (left + right)
        centre = sgn * (s - flank_mean)
        near = np.maximum(sgn * (_shift(s, -2) - flank_mean), sgn * (_shift(s, 2) - flank_mean))
        peak = (sgn * s >= sgn * _shift(s, -1)) & (sgn * s >= sgn * _shift(s, 1))
        ok = (c > 0) & peak & (np.abs(left - right) < centre)
        z = np.where(ok & (c > np.abs(z)), sgn * c, z)
        thin |= ok & (near <= THIN_RATIO * centre)
    # the profile of grain alone sets the unit: the robust spread of the raw centre
    # difference over the frame (lines are too few to move it)
    raw = s - 0.5 * (left + right)
    inner = raw[:, LINE_FLANK:-LINE_FLANK] if raw.shape[1] > 2 * LINE_FLANK + 2 else raw
    scale = float(1.4826 * np.median(np.abs(inner - np.median(inner)))) + 1e-9
    return z / scale, thin, raw / scale


def static_scratches(G: np.ndarray, threshold: float, min_length: int) -> np.ndarray:
    """Scratches that stay in place: thin, long, near-vertical lines of the frames
    themselves that persist over neighbouring frames (see the module's notes).

    Parameters
    ----------
    G : numpy.ndarray
        Grey frames (T, H, W), float.
    threshold : float
        Robust noise units a line's centre must stand off its flanks.
    min_length : int
        Rows a run must span.

    Returns
    -------
    numpy.ndarray
        Bool (T, H, W), the scratches' pixels.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> G = 0.5 + 0.01 * rng.standard_normal((5, 48, 40))
    >>> G[:, 4:44, 20] = 0.1
    >>> bool(static_scratches(G, 1.5, 24)[2, 4:44, 20].mean() > 0.8)
    True
    """
    T, ny, nx = G.shape
    ev = [line_evidence(G[t]) for t in range(T)]
    out = np.zeros((T, ny, nx), bool)
    foot = np.ones((1, 2 * DRIFT + 1), bool)
    for sgn in (1.0, -1.0):
        cand = np.stack([(sgn * z > threshold) & thin for z, thin, _ in ev])
        # weaker evidence suffices in the other frames: the line must be there, not strong
        seen = np.stack(
            [
                ndimage.binary_dilation((sgn * z > 0.5 * threshold) & thin, structure=foot)
                for z, thin, _ in ev
            ]
        )
        for t in range(T):
            others = [u for u in range(t - 2, t + 3) if u != t and 0 <= u < T]
            if len(others) < 2:
                continue
            votes = sum(seen[u].astype(np.int8) for u in others)
            hit = cand[t] & (votes >= min(VOTES, len(others)))
            if not hit.any():
                continue
            hit = ndimage.binary_closing(hit, structure=np.ones((BRIDGE_ROWS, 1), bool)) | hit
            labels, n = ndimage.label(
                hit, structure=np.array([[1, 1, 1], [0, 1, 0], [1, 1, 1]], bool)
            )
            if n == 0:
                continue
            keep = np.zeros(n + 1, bool)
            for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
                h = sl[0].stop - sl[0].start
                w = sl[1].stop - sl[1].start
                # long and near-vertical: tall, and no wider than its drift allows
                keep[idx] = h >= min_length and w <= 3 + h // 20
            core = keep[labels]
            if not core.any():
                continue
            # the scratch's own width: the columns up to two pixels beside the centre that
            # share its sign and stand out by part of the threshold
            prof = ev[t][2]
            wide = ndimage.binary_dilation(core, structure=np.ones((1, 5), bool))
            out[t] |= core | (wide & (sgn * prof > WIDTH_SHARE * threshold))
    return out
