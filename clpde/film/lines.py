"""Line scratches that stay in place: a spatial, per-frame thin-line detector with
continuity over frames.

The temporal detector of clpde.film.detect sees a scratch only where the scene moves past
it; in a static shot or near the centre of a slow zoom the compensated neighbours carry the
same scratch and the residual is flat. This detector looks at each frame itself: a
vertically smoothed frame, across each column a line profile (the centre against its flanks
at LINE_FLANK pixels), kept where

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
from scipy import ndimage

LINE_FLANK = 3  # flanks 3 pixels either side: lines up to 3-4 px wide
THIN_RATIO = 0.5  # two pixels out, the profile keeps at most this share of the centre's
DRIFT = 1  # pixels a scratch may move between the frames compared
SMOOTH_ROWS = 6.0  # Gaussian along y (rows) before the profile: grain averages out
WIDTH_SHARE = 0.4  # beside the centre, a scratch's pixels stand out by this share
VOTES = 3  # frames around it that must show the line (all of them at the film's ends)
BRIDGE_ROWS = 9  # gaps of a few rows bridged (a scratch fades in places)


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
