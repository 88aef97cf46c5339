"""The ghosts of the neighbours' scratches in a frame's residual, near a film's ends.

Where a frame's neighbours lie mostly on one side (a film's first and last frames, and the
frame next to them, with one neighbour on its short side), the temporal residual the
scratch detector reads (clpde.film._order.second_least) can be the frame against two
neighbours on one side that both carry a scratch: a frame without one then shows the
scratch in its residual with the opposite sign (the frame before a scratch begins at a
film's start). Such a run of the residual's line is a ghost where the frame beside it,
towards the film's inside, shows a line of the opposite sign at the run's place (a scratch
drifts a pixel a frame at most, clpde.film.lines.LINE_DRIFT); a scratch of the frame itself
leaves no line of the other sign there. The lines are the frames' own
(clpde.film.lines.frame_lines), at the level a neighbouring frame's line needs to vote for
a scratch (clpde.film.lines.film_scratches).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .lines import LINE_DRIFT, LINE_SCALE, LINE_SEEN, RUN_SUPPORT, frame_lines, scratch_runs


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
    frames `beside` (their `own_lines`).

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
    wide = np.ones((1, 2 * (LINE_DRIFT + 1) + 1), bool)
    for sgn in (1, -1):
        mine = runs == sgn
        if not mine.any():
            continue
        other = np.zeros(runs.shape, bool)
        for lines in beside:
            other |= ndimage.binary_dilation(lines == -sgn, structure=wide)
        labels, n = ndimage.label(mine, structure=np.ones((3, 3), bool))
        index = np.arange(1, n + 1)
        share = ndimage.mean(other, labels, index)
        ghost = np.concatenate([[False], share >= RUN_SUPPORT])
        out[ghost[labels]] = 0
    return out


def residual_runs(
    G: np.ndarray, scores: dict, t: int, threshold: float, min_length: int
) -> tuple[np.ndarray, np.ndarray]:
    """Frame t's scratch runs in its temporal residual (clpde.film.lines.scratch_runs on
    clpde.film.detect.film_scores' evidence), and the runs dropped as ghosts (`drop_ghosts`,
    where the frame is `one_sided`; the frames beside it read their own lines only, so a
    frame's runs read frames t - 1 .. t + 1 beyond its scores): bool (H, W) each. A
    ghost's residual is explained (a neighbour's scratch): no blotch is sought there."""
    sigmas, T = scores["sigma"], len(G)
    runs = scratch_runs(
        scores["zc"][t], scores["least"][t], sigmas[t], threshold, min_length, signed=True
    )
    kept = runs
    if one_sided(t, T, scores["radius"]) and runs.any():
        near = [u for u in (t - 1, t + 1) if 0 <= u < T]
        kept = drop_ghosts(runs, [own_lines(G[u], sigmas[u], threshold) for u in near])
    return kept != 0, (runs != 0) & (kept == 0)
