"""Line scratches: thin, long, near-vertical lines, found in a residual or in the frames.

Two detectors share this module. The line response of a residual (kernels/film/detect.cl),
which the temporal detector of clpde.film.detect runs on each frame minus its compensated
neighbours and a single image's detector on the image minus its horizontal median: a column
mean of the clamped residual, a thin-line response across it in robust noise units, summed
with the previous and next frames' within a pixel of drift (`LineKernels`); then the long
vertical runs of it whose rows mostly show the line (`scratch_runs`).

Scratches found in the frames themselves (`film_scratches`). The temporal detector sees a
scratch only where the scene moves past it fast enough: a scratch drifts slowly and persists
over frames, so the compensated neighbours carry nearly the same scratch and the residual is
flat. This detector looks at each frame (after Kokaram's and Joyeux et al.'s line models): a
scratch is a thin, nearly vertical, long line whose cross-profile is a narrow peak or dip
against the pixels 3-5 columns either side, with a roughly constant deviation along it.

- Per row, the line's contrast against the worse of its flanks (an edge is no line), where
  the profile is thin, in robust units of the frame's profile (at least the grain's, from
  the noise model); its mean over LINE_HALF rows either side: texture's lines are short.
- Continuity: LINE_VOTES of the frames within two show a line of the same sign within
  LINE_DRIFT columns per frame apart (a scene line in a pan leaves that window).
- Long and straight: runs bridged over gaps of LINE_GAP rows (an edge or a saturated area
  crossed), at least min_length rows, centres on a nearly vertical straight line.
- The mask: a band about the line's sub-pixel centre, as wide as its mean cross-profile
  (a line wider than a scratch is none), trimmed at the ends to the rows whose deviation
  keeps LINE_ENDS of its median; a line between two of the other sign is their gap.
- Scene structure (posts, poles, limbs) is thin and straight too. The line is followed
  into the frames either side, where the scene's motion (its flanks' flow) puts it: its
  halves must move as one (a limb above a post does not); a line that keeps its place in
  the scene is a scratch only where its deviation is shown to be added to the picture, not
  its own shade against the background (`_follows_content`). A scratch that never moves,
  of one shade, in a still shot is a post to the eye and here: left alone (do no harm).
- Confirmed: the frame before or after has the line too (one frame's chance alignment of
  a limb, a post and an edge is not a scratch).
Frame t's lines read frames t +- (radius + 1) at most: a window's context (film.stream).
Constants chosen on the calibration half of benchmarks/film_corpus.py (docs/film.md).
"""

from __future__ import annotations

import functools

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from ..imagedata import noise_std
from ._morph import close, dilate, extreme1d
from ._motion import map_frames
from ._order import median_of

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("film/detect.cl",)

# Scratches found in the frames themselves (film_scratches; chosen on the calibration half):
LINE_FLANK = (3, 5)  # the flanks' columns either side of the centre
LINE_ROWS = 1.5  # Gaussian along y (rows) before the profile
LINE_WIDTH = 4  # columns above half the peak, at most (scratches are 1-3 px wide)
LINE_CLIP = 8.0  # one row's contrast counts at most this (robust units)
LINE_MISS = 1.0  # a row without a thin line counts against the run by this
LINE_HALF = 12  # rows either side of the windowed mean
LINE_SCALE = 2.0 / 3.0  # the windowed mean's threshold, a share of scratch_threshold
LINE_SEEN = 0.5  # share of that threshold a neighbouring frame's line needs
LINE_DRIFT = 1  # columns a scratch may move from one frame to the next
LINE_VOTES = 2  # frames of the up-to-four within two that must show it
LINE_GAP = 31  # rows bridged where a scratch crosses an edge or saturates
LINE_COVER = 0.5  # share of a run's rows that show the line
LINE_SLOPE = 0.025  # columns per row: nearly vertical
LINE_STRAIGHT = 0.7  # share of the rows whose centre is within 1.5 px of the fitted line
LINE_BAND = 0.9  # the mask's half width, a share of the width at half the peak
LINE_REACH = 3.0  # ... at most this many pixels
LINE_ENDS = 0.3  # the ends: rows whose deviation keeps this share of the line's median
LINE_STILL = 0.1  # px per frame: a line drifting less against the scene is the scene's
LINE_ADDITIVE = 0.5  # a still line's slope on its flanks' level: nearer 0 (added) than -1
LINE_RIGID = 1.0  # px: a line's halves may move apart by this much between frames
LINE_PAN = 0.5  # px per frame: the scene's motion below which a shot is taken for still
LINE_FLOW = (4, 8)  # the columns either side whose flow is the scene's motion at a line
# The line response of a residual (the temporal detector's, and the spatial one's):
COLUMN_HALF = 12  # rows each side of the column mean
RESPONSE_FLANK = 3  # the response's flanks at 3 and 4 pixels: lines up to 5 px wide
RUN_SUPPORT = 0.5  # share of a scratch run's rows whose residual shows the line


def robust_scale(a: np.ndarray) -> float:
    """The median absolute deviation of a's finite values, as a Gaussian's deviation."""
    a = a[np.isfinite(a)]
    if a.size == 0:  # NaN, as np.median of nothing gave (without its warning)
        return float("nan")
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
            own = dilate(lines == sgn, structure=np.ones((1, 3), bool))
            hit &= own
        if not hit.any():
            continue
        # bridge gaps of a few rows (a scratch fades in places)
        hit = close(hit, np.ones((7, 1), bool)) | hit
        labels, n = ndimage.label(hit, structure=np.array([[0, 1, 0]] * 3, bool))
        if n == 0:
            continue
        # the runs' counts read their own pixels only (ys, xs; columns wrap as np.roll's)
        ys, xs = np.nonzero(labels)
        lab = labels[ys, xs]
        sizes = np.bincount(lab, minlength=n + 1)
        # np.roll(resid, off, axis=1) at the pixels
        beside = {off: resid[ys, (xs - off) % nx] for off in (-5, -4, -3, -1, 0, 1, 3, 4, 5)}
        shown3 = np.maximum(np.maximum(sgn * beside[0], sgn * beside[1]), sgn * beside[-1])
        support = np.bincount(lab, weights=shown3 > 2.0 * sigma, minlength=n + 1)
        # a scratch is thin: beside it, 3 to 5 columns away on both sides, the residual is
        # quiet in most rows; an object the flow missed leaves a broad residual
        quiet = np.ones(len(ys), bool)
        for off in (-5, -4, -3, 3, 4, 5):
            quiet &= np.abs(beside[off]) < 2.0 * sigma
        calm = np.bincount(lab, weights=quiet, minlength=n + 1)
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
        rows = close(shows, np.ones((9, 1), bool)) | shows
        wide = dilate(core, structure=np.ones((1, 3), bool))
        out[(core & rows) | (wide & (s > 0.5 * threshold) & shows)] = int(sgn)
    return out if signed else out != 0


def _columns(a: np.ndarray, reach: int):
    """A function of dx giving a moved by dx columns (a[:, x + dx] at x, edges repeated), for
    |dx| <= reach: views of one padded copy."""
    nx = a.shape[1]
    padded = np.pad(a, ((0, 0), (reach, reach)), mode="edge")
    return lambda dx: padded[:, reach + dx : reach + dx + nx]


@functools.cache
def _profile_gain() -> float:
    """The profile's deviation for white noise of deviation 1: the row Gaussian's and the
    centre-minus-flanks' weights (the grain's floor of the profile's unit)."""
    w = ndimage.gaussian_filter1d(np.eye(1, 41, 20)[0], LINE_ROWS)
    n = LINE_FLANK[1] - LINE_FLANK[0] + 1
    return float(np.sqrt(np.sum(w**2) * (1.0 + 2.0 * n * (0.5 / n) ** 2)))


def frame_lines(g: np.ndarray, grain: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One frame's line evidence: per sign, the windowed mean of the rows' thin-line contrast
    at the columns where it peaks across x (0 elsewhere); and the profile.

    Parameters
    ----------
    g : numpy.ndarray
        One grey frame (H, W), float.
    grain : float
        The grain's deviation (the noise model's): the unit is at least its share of the
        profile.

    Returns
    -------
    m : numpy.ndarray
        (2, H, W) float32: bright lines, then dark ones, in robust units.
    prof : numpy.ndarray
        (H, W) float32: each pixel against the mean of its flanks, in the same units.
    flank : tuple of (numpy.ndarray, float)
        The mean of the flanks (H, W) and the unit, in grey.

    Examples
    --------
    >>> import numpy as np
    >>> g = 0.5 + 0.01 * np.random.default_rng(0).standard_normal((60, 40))
    >>> g[:, 20] = 0.3
    >>> m, prof, _ = frame_lines(g, 0.01)
    >>> int(np.argmax(m[1, 30])) in (19, 20, 21), bool(m[1, 30].max() > 3 and prof[30, 20] < -3)
    (True, True)
    """
    s = ndimage.gaussian_filter1d(g.astype(np.float32), LINE_ROWS, axis=0, mode="nearest")
    a, b = LINE_FLANK
    at = _columns(s, b)
    left = sum(at(-k) for k in range(a, b + 1)) / (b - a + 1)
    right = sum(at(k) for k in range(a, b + 1)) / (b - a + 1)
    prof = s - 0.5 * (left + right)
    inner = prof[::2, b:-b:2] if prof.shape[1] > 2 * b + 2 else prof
    # the unit: the profile's robust spread over the frame (every other row and column:
    # lines are too few to move it; texture raises it, as it raises the lines it makes),
    # at least the grain's
    unit = max(robust_scale(inner), _profile_gain() * grain)
    prof = prof / unit
    near = _columns(prof, 3)
    out = np.zeros((2,) + s.shape, np.float32)
    for i, sgn in enumerate((1.0, -1.0)):
        # against the worse flank: an edge beside a line, or an edge alone, is no line
        c = (sgn * s - np.maximum(sgn * left, sgn * right)) / unit
        half = 0.5 * sgn * prof
        above = sum((sgn * near(k) > half).astype(np.int8) for k in range(-3, 4))
        r = np.where((c > 0) & (above <= LINE_WIDTH), np.minimum(c, LINE_CLIP), -LINE_MISS)
        r = extreme1d(r, 3, 1, "nearest")  # a column of wander
        m = ndimage.uniform_filter1d(r, 2 * LINE_HALF + 1, axis=0, mode="constant", cval=-LINE_MISS)
        beside = _columns(m, 1)
        peak = (m >= beside(-1)) & (m > beside(1))
        out[i] = np.where(peak, m, 0.0)
    return out, prof, (0.5 * (left + right), unit)


def _runs(hit: np.ndarray, ps: np.ndarray, min_length: int) -> list[tuple[int, int, np.ndarray]]:
    """The long, straight, nearly vertical runs of a frame's line hits: (first row, stop
    row, the fitted line's (slope, intercept) in columns per row); ps: the profile, signed
    so that the line is positive."""
    wide = extreme1d(hit.view(np.uint8), 3, 1)
    # gaps of up to LINE_GAP rows closed (a maximum, then a minimum along y)
    closed = extreme1d(extreme1d(wide, LINE_GAP, 0, "constant"), LINE_GAP, 0, lowest=True)
    closed = (closed | wide).view(bool)
    wide = wide.view(bool)
    labels, _ = ndimage.label(closed, structure=np.ones((3, 3), bool))
    runs = []
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        comp = labels[sl] == idx
        rows = np.nonzero(comp.any(1))[0]
        if rows[-1] - rows[0] + 1 < min_length:
            continue
        if (comp & hit[sl]).any(1)[rows[0] : rows[-1] + 1].mean() < LINE_COVER:
            continue
        # per row, the centre: the run's column of the largest profile; a straight line
        # through them (refitted on the rows within 1.5 px, where it crosses an edge the
        # largest profile may be the edge's)
        cx = np.argmax(np.where(comp, ps[sl], -np.inf), axis=1)[rows]
        fit = np.polyfit(rows, cx, 1)
        near = np.abs(cx - np.polyval(fit, rows)) <= 1.5
        if near.sum() >= 2:
            fit = np.polyfit(rows[near], cx[near], 1)
            near = np.abs(cx - np.polyval(fit, rows)) <= 1.5
        if abs(fit[0]) > LINE_SLOPE or near.mean() < LINE_STRAIGHT:
            continue
        y0 = sl[0].start
        fit = np.array([fit[0], fit[1] + sl[1].start - fit[0] * y0])
        runs.append((y0 + int(rows[0]), y0 + int(rows[-1]) + 1, fit))
    return runs


def _centre(ps: np.ndarray, yy: np.ndarray, xc: np.ndarray, reach: int = 1):
    """The line's mean cross-profile over rows yy about columns xc: (sub-pixel offset of its
    centre from xc, width at half its peak, the peak), its peak sought within reach
    columns of xc; None where nothing stands out there."""
    nx = ps.shape[1]
    offs = np.arange(-6, 7)
    cols = np.clip(np.rint(xc).astype(int)[:, None] + offs, 0, nx - 1)
    mp = ps[yy[:, None], cols].mean(axis=0)
    j = 6 - reach + int(np.argmax(mp[6 - reach : 7 + reach]))
    if mp[j] <= 0:
        return None
    hm = 0.5 * mp[j]
    lo = hi = j
    while lo > 0 and mp[lo - 1] > hm:
        lo -= 1
    while hi < 12 and mp[hi + 1] > hm:
        hi += 1
    # sub-pixel crossings of half the peak either side
    xl = lo - (mp[lo] - hm) / max(mp[lo] - mp[lo - 1], 1e-9) if lo > 0 else lo - 0.5
    xr = hi + (mp[hi] - hm) / max(mp[hi] - mp[hi + 1], 1e-9) if hi < 12 else hi + 0.5
    return 0.5 * (xl + xr) - 6 + (np.rint(xc) - xc).mean(), xr - xl, mp[j]


def _band(ps: np.ndarray, y0: int, y1: int, fit: np.ndarray, min_length: int):
    """A run's scratch: (first row, stop row, sub-pixel centre per row, half width,
    contrast), its width and centre from the mean cross-profile along it, its ends where
    its deviation keeps LINE_ENDS of its median; None where nothing long is left."""
    nx = ps.shape[1]
    yy = np.arange(y0, y1)
    xc = np.polyval(fit, yy)
    got = _centre(ps, yy, xc)
    if got is None or got[1] > LINE_WIDTH + 0.5:
        return None  # wider than a scratch: a post, a limb, an object's edge
    cen = xc + got[0]
    half = min(LINE_BAND * got[1], LINE_REACH)
    dev = ps[yy, np.clip(np.rint(cen).astype(int), 0, nx - 1)]
    on = ndimage.uniform_filter1d(dev, 9, mode="nearest") >= LINE_ENDS * np.median(dev)
    if not on.any():
        return None
    a0, a1 = int(np.argmax(on)), len(on) - int(np.argmax(on[::-1]))
    if a1 - a0 < min_length:
        return None
    return y0 + a0, y0 + a1, cen[a0:a1], half, float(np.median(dev[a0:a1]))


def _track(line: tuple, t: int, ev: list, scene_dx: float, span: int) -> list[tuple[int, list]]:
    """The line's place in frame t and the frames up to span either side, against where the
    scene's motion puts it: per frame u, (u - t, offsets in px of the whole line, its
    upper half and its lower half, None where that part shows no such line)."""
    sgn, y0, y1, cen, _, contrast = line
    yy = np.arange(y0, y1)
    mid = (y1 - y0) // 2
    parts = (slice(None), slice(None, mid), slice(mid, None))
    out = []
    for u in range(t - span, t + span + 1):
        if not 0 <= u < len(ev):
            continue
        offs = []
        for part in parts:
            got = _centre(sgn * ev[u][1], yy[part], (cen + (u - t) * scene_dx)[part], reach=2)
            # the same line: as thin, and as strong within a factor of two (a frame before
            # the scratch appears shows whatever the scene has there)
            ok = got is not None and got[1] <= LINE_WIDTH + 0.5 and got[2] >= 0.5 * contrast
            offs.append(got[0] if ok else None)
        out.append((u - t, offs))
    return out


def _rigid(track: list) -> bool:
    """Whether a line's halves move as one from frame t to the others: apart by more than
    LINE_RIGID px in fewer than two frames (a limb above a post does not; one frame's half
    may be caught by something passing by)."""
    here = dict(track)[0]
    if here[1] is None or here[2] is None:
        return True
    apart = [
        abs((top - here[1]) - (bottom - here[2])) > LINE_RIGID
        for _, (_, top, bottom) in track
        if top is not None and bottom is not None
    ]
    return sum(apart) < 2


def _still(track: list) -> bool:
    """Whether a line keeps its place in the scene: its drift against the scene's motion,
    fitted over the frames, at most LINE_STILL px per frame (a post, a pole, a door frame;
    in a still shot, a scratch that never moves is one too, to the eye and here)."""
    seen = [(k, offs[0]) for k, offs in track if offs[0] is not None]
    if dict(track)[0][0] is None or len(seen) < 3:
        return False
    ks = np.array([k for k, _ in seen], float)
    offs = np.array([o for _, o in seen])
    # the drift: the slope of the offsets over the frames (least squares)
    ks, offs = ks - ks.mean(), offs - offs.mean()
    return abs(float(np.dot(ks, offs) / np.dot(ks, ks))) <= LINE_STILL


def _scene_dx(flows: np.ndarray | None, t: int, T: int, yy: np.ndarray, cen: np.ndarray) -> float:
    """The scene's motion along x per frame at a line: the median flow of the columns
    LINE_FLOW px either side of it (the line's own flow may follow the line), forward to
    t + 1 and backward from t - 1 averaged; 0 below LINE_PAN or without flows (a still
    shot)."""
    if flows is None:
        return 0.0
    ks = [k for k in (-1, 1) if 0 <= t + k < T]
    nx = flows.shape[2]
    a, b = LINE_FLOW
    offs = np.r_[-b : -a + 1, a : b + 1]
    cols = np.clip(np.rint(cen).astype(int)[:, None] + offs, 0, nx - 1)
    per = [k * np.median(f[yy[:, None], cols, 0]) for k, f in zip(ks, flows, strict=True)]
    dx = float(np.mean(per))
    # below LINE_PAN the flow's own error (a few tenths of a pixel) is as large as a slow
    # scratch's drift: a still shot
    return dx if abs(dx) >= LINE_PAN else 0.0


def _follows_content(line: tuple, prof: np.ndarray, flank: np.ndarray, unit: float) -> bool:
    """Whether a line's deviation follows the content it crosses rather than keeping its
    own size. A scratch adds to or takes from the picture (Kokaram's model): regressed on
    its flanks' level along it, its deviation has a slope of 0; a post of its own shade
    has its shade minus the background's, a slope of -1. A line is the scene's unless
    the slope's 95% interval lies within LINE_ADDITIVE of 0 (nearer 0 than -1): flanks
    of one level all along, or a slope between, leave it to the scene (do no harm)."""
    _, y0, y1, cen, _, _ = line
    yy = np.arange(y0, y1)
    xi = np.clip(np.rint(cen).astype(int), 0, flank.shape[1] - 1)
    f = flank[yy, xi].astype(np.float64)
    d = prof[yy, xi].astype(np.float64) * unit  # the deviation, signed, in grey
    f, d = f - f.mean(), d - d.mean()
    spread = float(np.sqrt(np.mean(f**2)))
    if spread == 0.0:
        return True
    beta = float(np.mean(f * d)) / spread**2
    # the slope's standard error, the rows counted in fours (the profile's row smoothing
    # and the grain correlate neighbouring rows)
    se = float(np.std(d - beta * f)) / (spread * np.sqrt(max(len(yy) / 4.0, 1.0)))
    # a scratch only where the slope's 95% interval lies nearer 0 (added) than -1 (a shade)
    return abs(beta) + 2.0 * se > LINE_ADDITIVE


def _in_gap(line: tuple, found: list) -> bool:
    """Whether a line lies between two lines of the other sign, within LINE_FLANK[1] + 1 px
    either side over half its rows: the gap of two scratches, seen with them for flanks."""
    sgn, y0, y1, cen, _, _ = line
    sides = set()
    for osgn, o0, o1, ocen, _, _ in found:
        a, b = max(y0, o0), min(y1, o1)
        if osgn == sgn or b <= a:
            continue
        gap = ocen[a - o0 : b - o0] - cen[a - y0 : b - y0]
        for side in (-1, 1):
            near = (side * gap > 0) & (side * gap <= LINE_FLANK[1] + 1)
            if near.sum() >= 0.5 * (y1 - y0):
                sides.add(side)
    return len(sides) == 2


def film_scratches(
    G: np.ndarray,
    threshold: float,
    min_length: int,
    grain: np.ndarray | None = None,
    flows: list | None = None,
    radius: int = 2,
) -> np.ndarray:
    """Line scratches found in the frames themselves, confirmed over neighbouring frames
    (see the module's notes).

    Parameters
    ----------
    G : numpy.ndarray
        Grey frames (T, H, W), float.
    threshold : float
        The scratch threshold (robust noise units; the windowed mean needs LINE_SCALE of it).
    min_length : int
        Rows a scratch must span.
    grain : numpy.ndarray, optional
        The grain's deviation per frame (the film's noise model); default: each frame's
        own fine-scale estimate.
    flows : list of numpy.ndarray, optional
        Per frame, its flows to the previous and next frames that exist ((K, H, W, 2), x
        first; the film detector's): the scene's motion at a line. Default: none (every
        line is taken for one in a still shot).
    radius : int
        The film detector's radius: frames up to min(2, radius) either side confirm a line
        and follow it, so that frame t's lines read frames t - radius - 1 .. t + radius + 1
        only (the context a window of the film gives the detector: clpde.film.stream).

    Returns
    -------
    numpy.ndarray
        Bool (T, H, W), the scratches' pixels.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> G = 0.5 + 0.01 * rng.standard_normal((5, 64, 48))
    >>> for t in range(5):
    ...     G[t, 4:60, 20 + t // 2] = 0.3  # a dark scratch, drifting
    >>> found = film_scratches(G, 3.0, 26)
    >>> bool(found[2, 4:60, 21].mean() > 0.9), int(found[:, :, :15].sum())
    (True, 0)
    """
    T, ny, nx = G.shape
    grain = [noise_std(G[t].astype(np.float64)) for t in range(T)] if grain is None else grain
    level = LINE_SCALE * threshold

    def lines_of(t: int) -> tuple:  # frame t's lines, and where seen per drift width, sign
        m = (got := frame_lines(G[t], float(grain[t])))[0]
        return got, [
            [extreme1d((m[i] > LINE_SEEN * level).view(np.uint8), w, 1) for i in (0, 1)]
            for w in (2 * LINE_DRIFT + 1, 4 * LINE_DRIFT + 1)
        ]

    ev, wide = zip(*map_frames(lines_of, range(T)), strict=True)  # frames in threads
    # seen[dt - 1][u][sign]: frame u's lines, widened by the drift over dt frames
    seen = [[w[dt] for w in wide] for dt in (0, 1)]
    args = (ev, seen, level, min_length, flows, min(2, radius))  # min(2, radius): the span
    kept = map_frames(lambda t: _frame_scratches(t, *args), range(T))
    out = np.zeros((T, ny, nx), bool)
    xs = np.arange(nx)[None, :]
    for t in range(T):
        for line in kept[t]:
            # confirmed: the previous or next frame has the line too (one frame's chance
            # alignment of a limb, a post and an edge is not a scratch)
            near = [u for u in (t - 1, t + 1) if 0 <= u < T]
            if not any(_same_line(line, other) for u in near for other in kept[u]):
                continue
            _, y0, y1, cen, half, _ = line
            out[t, y0:y1] |= np.abs(xs - cen[:, None]) <= half
    return out


def _same_line(a: tuple, b: tuple) -> bool:
    """Whether two frames' lines are one: one sign, over half the shorter one's rows,
    centres within LINE_DRIFT + 0.5 px."""
    if a[0] != b[0]:
        return False
    lo, hi = max(a[1], b[1]), min(a[2], b[2])
    if hi - lo < 0.5 * min(a[2] - a[1], b[2] - b[1]):
        return False
    gap = np.abs(a[3][lo - a[1] : hi - a[1]] - b[3][lo - b[1] : hi - b[1]])
    return bool(np.median(gap) <= LINE_DRIFT + 0.5)


def _frame_scratches(t: int, ev: list, seen: list, level: float, min_length: int, flows, span: int):
    """Frame t's scratch lines (sign, first row, stop row, centre per row, half width,
    contrast) before the confirmation by the frames beside it (film_scratches)."""
    T = len(ev)
    m, prof, (flank, unit) = ev[t]
    others = [u for u in range(t - span, t + span + 1) if u != t and 0 <= u < T]
    found = []
    for i, sgn in enumerate((1.0, -1.0)):
        votes = sum(seen[abs(u - t) - 1][u][i] for u in others)
        hit = (m[i] > level) & (votes >= min(LINE_VOTES, len(others)))
        if not hit.any():
            continue
        for y0, y1, fit in _runs(hit, sgn * prof, min_length):
            band = _band(sgn * prof, y0, y1, fit, min_length)
            if band is not None:
                found.append((sgn, *band))
    kept = []
    for line in found:
        if _in_gap(line, found):
            continue
        yy = np.arange(line[1], line[2])
        dx = _scene_dx(None if flows is None else flows[t], t, T, yy, line[3])
        track = _track(line, t, ev, dx, span)
        if not _rigid(track) or (_still(track) and _follows_content(line, prof, flank, unit)):
            continue
        kept.append(line)
    return kept
