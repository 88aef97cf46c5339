"""The ghosts of the neighbours' scratches in a frame's residual, near a film's ends.

Where a frame's neighbours lie mostly on one side (a film's first and last frames, and the
frame next to them, with one neighbour on its short side), the temporal scratch detector
(clpde.film.lines.scratch_runs) can find a scratch a frame does not have: its residual
(clpde.film._order.second_least) may be the frame against two neighbours on one side that
both carry a scratch, showing it with the opposite sign (the frame before a scratch begins
at a film's start); and its line score sums the next frame's in (LineKernels.continuity),
showing the neighbour's scratch itself. So there a run counts only

- where the frame shows a line of the run's sign itself (a scratch is a line in the frame),
- and not where a frame beside it shows a line of the opposite sign at the run's place,
  along the motion, within LINE_DRIFT + 1 px (a scratch of the frame itself leaves no
  line of the other sign there).

The lines are the frames' own (clpde.film.lines.frame_lines), at the level a neighbouring
frame's line needs to vote for a scratch (clpde.film.lines.film_scratches). The runs
dropped are the ghosts: their residual is explained, and no blotch is sought there.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ._morph import dilate
from .lines import (
    LINE_DRIFT,
    LINE_SCALE,
    LINE_SEEN,
    RUN_SUPPORT,
    frame_lines,
    scratch_runs,
)


def one_sided(t: int, count: int, radius: int) -> bool:
    """Whether frame t of `count` has fewer than `radius` frames on a side (then its
    residual's second least difference may come from one side's two frames)."""
    return t < radius or t >= count - radius


def own_lines(g: np.ndarray, grain: float, threshold: float) -> np.ndarray:
    """The frame's own thin lines: +1 bright, -1 dark, 0 none (int8, (H, W)), where the
    windowed line contrast of clpde.film.lines.frame_lines reaches what a neighbouring
    frame's line needs to confirm a scratch (LINE_SEEN of LINE_SCALE of the threshold).

    Parameters
    ----------
    g : numpy.ndarray
        One grey frame (H, W), float.
    grain : float
        The grain's deviation (the film's noise model).
    threshold : float
        The scratch threshold (robust noise units).

    Returns
    -------
    numpy.ndarray
        int8 (H, W): the sign of the line at its peak column, 0 elsewhere.

    Examples
    --------
    >>> g = 0.5 + 0.01 * np.random.default_rng(0).standard_normal((80, 40))
    >>> g[:, 20] -= 0.1  # a dark line
    >>> signs = own_lines(g, 0.01, 3.0)
    >>> int(signs[40, 19:22].min()), int(np.abs(signs[:, :15]).sum())
    (-1, 0)
    """
    m, _, _ = frame_lines(g, grain)
    level = LINE_SEEN * LINE_SCALE * threshold
    return np.where(m[0] > level, 1, np.where(m[1] > level, -1, 0)).astype(np.int8)


def drop_ghosts(runs: np.ndarray, beside: list[np.ndarray]) -> np.ndarray:
    """The signed scratch runs of a frame (+1, -1, 0; clpde.film.lines.scratch_runs with
    signed=True) without those that are ghosts: runs of which at least RUN_SUPPORT of the
    pixels lie within LINE_DRIFT + 1 columns of a line of the opposite sign in one of the
    frames `beside` (their `own_lines`, at the frame's place).

    Parameters
    ----------
    runs : numpy.ndarray
        int8 (H, W): the runs' signs.
    beside : list of numpy.ndarray
        The own_lines of the frames next to this one.

    Returns
    -------
    numpy.ndarray
        int8 (H, W): the runs that are not ghosts.

    Examples
    --------
    >>> runs = np.zeros((40, 20), np.int8); runs[:, 8] = -1  # a dark run in the residual
    >>> nxt = np.zeros((40, 20), np.int8); nxt[:, 9] = 1  # the next frame's bright scratch
    >>> int(np.abs(drop_ghosts(runs, [nxt])).sum()), int(np.abs(drop_ghosts(runs, [-nxt])).sum())
    (0, 40)
    """
    out = runs.copy()
    drift = np.ones((1, 2 * (LINE_DRIFT + 1) + 1), bool)
    for sgn in (1, -1):
        other = np.zeros(runs.shape, bool)
        for lines in beside:
            other |= dilate(lines == -sgn, structure=drift)
        out[_mostly_on(runs == sgn, other)] = 0
    return out


def _mostly_on(mask: np.ndarray, where: np.ndarray) -> np.ndarray:
    """The components of mask (8-connected) of which at least RUN_SUPPORT lie on `where`."""
    labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    if n == 0:
        return mask
    share = ndimage.mean(where, labels, np.arange(1, n + 1))
    return np.concatenate([[False], share >= RUN_SUPPORT])[labels]


def residual_runs(
    G: np.ndarray, scores: dict, t: int, threshold: float, min_length: int
) -> tuple[np.ndarray, np.ndarray]:
    """Frame t's scratch runs in its temporal residual (clpde.film.lines.scratch_runs on
    clpde.film.detect.film_scores' evidence), and the runs dropped as ghosts (`drop_ghosts`,
    where the frame is `one_sided`; the frames beside it read their own lines only, so a
    frame's runs read frames t - 1 .. t + 1 beyond its scores, their lines pulled onto
    frame t by its flows to them), with the runs there that the frame does not show as a
    line of its own: bool (H, W) each. A ghost's residual is explained (a neighbour's
    scratch): no blotch is sought there."""
    sigmas, T = scores["sigma"], len(G)
    runs = scratch_runs(
        scores["zc"][t], scores["least"][t], sigmas[t], threshold, min_length, signed=True
    )
    kept = runs
    if one_sided(t, T, scores["radius"]) and runs.any():
        # a run counts only where the frame shows a line of its sign: near an end the
        # line score sums the next frame's in (clpde.film.lines.LineKernels.continuity),
        # whose scratch would otherwise carry over to a frame without one
        own = own_lines(G[t], sigmas[t], threshold)
        kept = scratch_runs(
            scores["zc"][t], scores["least"][t], sigmas[t], threshold, min_length, own, True
        )
        # the frames beside t, their lines brought to where frame t's flow to them puts
        # each pixel (the residual compares the frame with its compensated neighbours)
        near = [t + k for k in (-1, 1) if 0 <= t + k < T]
        beside = [
            _pulled(own_lines(G[u], sigmas[u], threshold), flow)
            for u, flow in zip(near, scores["flows"][t], strict=True)
        ]
        kept = drop_ghosts(kept, beside)
    return kept != 0, (runs != 0) & (kept == 0)


def _pulled(a: np.ndarray, flow: np.ndarray) -> np.ndarray:
    """a (H, W) of another frame read at each pixel's place there, by a flow (H, W, 2),
    x first, to the nearest pixel (edges repeated)."""
    ny, nx = a.shape
    # the places in float64 (a pixel index plus a float32 flow), rounded half to even
    y = np.rint(np.arange(ny, dtype=np.float64)[:, None] + flow[..., 1])
    x = np.rint(np.arange(nx, dtype=np.float64)[None, :] + flow[..., 0])
    y = np.clip(y, 0, ny - 1).astype(np.intp)
    x = np.clip(x, 0, nx - 1).astype(np.intp)
    return a.ravel()[y * nx + x]
