"""A second look at a frame's blotches, with flows their own damage does not drag (issue 34).

DIS cannot be told to ignore pixels: a blotch drags its frame's flows around it, the
compensated neighbours are misaligned there, and the residual flags a halo next to the
damage while the same disturbance hides some of its pixels (and the neighbours' spread
around them, which scales the evidence, grows). Once the detector has found frame t's
blotches, it looks again in a window around each, and only there (a second DIS round over
whole frames cost 58% more CPU a frame):

- frame t's flows to its neighbours (and at a film's ends their flows back) are mended:
  within DRAG px of a blotch a flow takes the value of the nearest pixel beyond (no flow
  is estimated again);
- frame t's evidence is scored again in the window with those flows, the grain's level,
  the region evidence's scale and the flicker fits of the whole frame kept;
- the second look changes a pixel only where the mended flows changed its evidence: a
  first-pass pixel goes where they took EXPLAINED of its residual away and it no longer
  reaches the low level (the drag made it), and a blotch grows, within TAKE px, into
  pixels they raised to the low level (the drag hid them).

It reads frame t, its neighbours' frames and flows, and frame t's first-pass blotches only,
which every window and chunk of a film holding frame t computes alike: one result however
the film is run.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
from scipy import ndimage

from ._grow import HYSTERESIS_LOW
from ._morph import dilate
from ._motion import FilmMotion, fb_error, loop_error

# px around a blotch whose flows are mended (chosen on the calibration half: 4, 8, 12 and
# 16 px gave 37.73, 37.89, 37.80 and 38.03 dB; 8 for its smaller windows)
DRAG = 8
TAKE = 6  # px around a first-pass blotch into which the second look may grow it
# The window's interior reaches REACH px past the blotches (the mended flows and what
# their evidence reads around them); the scores see MARGIN px more of context.
REACH = 14
MARGIN = 12
MOVED = 0.25  # px a mended flow must move somewhere for its window to be scored again
EXPLAINED = 0.5  # share of a pixel's residual the mended flows must take away
SCORED = ("d", "d_any", "any_in", "spread", "zr", "res", "both", "n")


def windows(blotch: np.ndarray) -> list[tuple[tuple[slice, slice], tuple[slice, slice]]]:
    """(interior, crop) per group of blotches within 2 REACH px of each other: the box
    REACH px around them, and that box with MARGIN px more, within the frame."""
    ny, nx = blotch.shape
    labels, _ = ndimage.label(dilate(blotch, REACH))
    out = []
    for sy, sx in ndimage.find_objects(labels):
        crop = (
            slice(max(sy.start - MARGIN, 0), min(sy.stop + MARGIN, ny)),
            slice(max(sx.start - MARGIN, 0), min(sx.stop + MARGIN, nx)),
        )
        out.append(((sy, sx), crop))
    return out


def _nearest(bad: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Each pixel's nearest pixel outside `bad` (itself outside it); None if bad is empty
    or everything."""
    if not bad.any() or bad.all():
        return None
    return ndimage.distance_transform_edt(bad, return_indices=True)[1]


def mend(flow: np.ndarray, near) -> np.ndarray:
    """flow (a crop) with each pixel given its _nearest pixel's value."""
    return flow.copy() if near is None else flow[near[0], near[1]]


def _mended_flows(
    motion: FilmMotion, t: int, offs: list[int], blotch: np.ndarray, wins: list
) -> dict:
    """Frame t's flows to its neighbours (and, at a film's ends, theirs back: the
    forward-backward check reads them) mended around its blotches."""
    bad = dilate(blotch, DRAG)
    nears = [_nearest(bad[crop]) for _, crop in wins]
    one_sided = all(k > 0 for k in offs) or all(k < 0 for k in offs)
    ny, nx = blotch.shape
    flows = {}
    for k in offs:
        s = t + k
        ahead = motion.flow(t, s).copy()
        back = motion.flow(s, t).copy() if one_sided else None
        for (_, crop), near in zip(wins, nears, strict=True):
            first = motion.flow(t, s)[crop]
            ahead[crop] = mend(first, near)
            if back is not None:
                # the neighbour's pixels that land on the blotch: the window displaced by
                # the flow's median there, within the frame
                dx, dy = (int(np.rint(np.median(first[..., i]))) for i in (0, 1))
                (sy, sx), (h, w) = crop, first.shape[:2]
                y0 = min(max(sy.start + dy, 0), ny - h)
                x0 = min(max(sx.start + dx, 0), nx - w)
                there = (slice(y0, y0 + h), slice(x0, x0 + w))
                back[there] = mend(motion.flow(s, t)[there], near)
        flows[(t, s)] = ahead
        if back is not None:
            flows[(s, t)] = back
    return flows


class WindowMotion(FilmMotion):
    """FilmMotion's neighbours and trust on a crop of the frames, with some flows replaced:
    coordinates stay the whole frame's, warps read the whole neighbour, and the flicker
    fits are the whole frame's (`full`'s)."""

    def __init__(self, full: FilmMotion, flows: dict, crop: tuple) -> None:
        self.full, self.flows, self.crop = full, flows, crop
        self.G = full.G[:, crop[0], crop[1]]
        self.keep = False
        self.T, self.ny, self.nx = self.G.shape
        self._local = full._local  # this thread's DIS of the frames: its remaps and filters
        self._lock = threading.Lock()
        self._kept: dict = {}
        gy, gx = np.mgrid[crop[0], crop[1]]
        self.gx, self.gy = gx.astype(np.float32), gy.astype(np.float32)

    def whole(self, a: int, b: int) -> np.ndarray:
        f = self.flows.get((a, b))
        return self.full.flow(a, b) if f is None else f

    def flow(self, t: int, s: int) -> np.ndarray:
        return self.whole(t, s)[self.crop]

    def warped(self, t: int, s: int) -> np.ndarray:
        return self._once(("w", t, s), lambda: self.warp(self.full.G[s], t, s))

    def inside(self, t: int, s: int) -> np.ndarray:
        def compute():
            xs, ys = self.coords(t, s)
            nx, ny = self.full.nx, self.full.ny
            return (xs >= 1) & (xs < nx - 2) & (ys >= 1) & (ys < ny - 2)

        return self._once(("in", t, s), compute)

    def gain(self, t: int, s: int) -> tuple[float, float]:
        return self.full.gain(t, s)

    def fb_error(self, t: int, s: int) -> np.ndarray:
        return fb_error(self.flow(t, s), self.warp(self.whole(s, t), t, s, "linear"))

    def loop_error(self, t: int, a: int, b: int) -> np.ndarray:
        fab = self.warp(self.whole(a, b), t, a, "linear")
        return loop_error(self.flow(t, a), fab, self.flow(t, b))


def look_again(
    scores: dict,
    t: int,
    blotch: np.ndarray,
    taken: np.ndarray,
    evidence: Callable[[dict], np.ndarray],
    threshold: float,
    frame_scores: Callable,
) -> np.ndarray:
    """Frame t's blotches after a second look around `blotch` (see the module text).

    scores: clpde.film.detect.film_scores' (with its "motion"); taken: pixels never blotches
    (the frame's scratches and their ghosts); evidence(scores): frame t's blotch evidence
    in noise units (clpde.film.detect.blotch_evidence); threshold: the blotch threshold;
    frame_scores: clpde.film.detect.frame_scores."""
    motion: FilmMotion = scores["motion"]
    T = motion.T
    radius = int(scores["radius"])
    offs = [k for k in range(-radius, radius + 1) if k != 0 and 0 <= t + k < T]
    wins = windows(blotch)
    if not wins or len(offs) < 2:
        return blotch
    flows = _mended_flows(motion, t, offs, blotch, wins)
    fixed = {"sigma": scores["sigma"][t], "zr_scale": scores["zr_scale"][t]}
    # the blotch evidence with the first flows and with the mended ones, and the residual
    before = np.zeros(blotch.shape, np.float32)
    after = np.zeros(blotch.shape, np.float32)
    res = scores["res"][t].copy()
    seen = scores["n"][t] > 0
    for inner, crop in wins:
        moved = max(
            float(np.abs(flows[(t, t + k)][inner] - motion.flow(t, t + k)[inner]).max())
            for k in offs
        )
        if moved < MOVED:
            continue  # the same evidence as the first look's
        got = frame_scores(WindowMotion(motion, flows, crop), t, radius, fixed)
        rel = tuple(
            slice(i.start - c.start, i.stop - c.start) for i, c in zip(inner, crop, strict=True)
        )
        again, first = dict(scores), dict(scores)
        for key in (*SCORED, "flows", "bridge"):
            again[key] = {t: got[key]}
        for key in SCORED:
            first[key] = {t: scores[key][t][crop]}
        before[inner] = evidence(first)[rel]
        after[inner] = evidence(again)[rel]
        res[inner], seen[inner] = got["res"][rel], got["n"][rel] > 0
    low = after > HYSTERESIS_LOW * threshold
    # a first-pass pixel goes where the mended flows took EXPLAINED of its residual away
    # (the residual's, not the evidence's: that is 0 where a side lost its trust, which
    # says nothing) and it no longer reaches the low level: a halo's residual was the
    # flow's error, a faint rim's is the damage's and stays
    explained = seen & (np.abs(res) < (1.0 - EXPLAINED) * np.abs(scores["res"][t])) & ~low
    # a blotch grows only into pixels whose evidence the mended flows raised to the low
    # level (the drag hid them): elsewhere the first look saw the same evidence and decided
    hidden = low & (after > before) & ~taken
    return (blotch & ~explained) | dilate(blotch, TAKE, within=blotch | hidden)
