"""A second look at a frame's blotches, with flows their own damage does not drag (issue 34).

DIS cannot be told to ignore pixels: a blotch drags its frame's flows around it, the
compensated neighbours are misaligned there, and the residual flags a halo next to the
damage while the same disturbance hides some of its pixels. Once the detector has found
frame t's blotches, it looks again in a window around each, and only there (a second DIS
round over whole frames cost 58% more CPU a frame):

- frame t's flows (and at a film's ends its neighbours' flows back) are mended around the
  blotches: within DRAG px of one, a flow takes the value of the nearest pixel beyond,
  inside the blotch always, around it where that brings the neighbour nearer the frame
  (no flow is estimated again; DIS on the window of the roughly filled frame, MEND False,
  is kept for comparison);
- frame t's evidence is scored again in the window with those flows, the grain's level
  and the flicker fits of the whole frame kept, and the blotch checks run again in the
  window, with candidates in its interior only and the frame's own levels (CHAIN; else
  the evidence alone decides);
- the second look changes a pixel only where the mended flows changed its evidence: a
  first-pass pixel goes where they took EXPLAINED of it away (the drag made it), a new
  pixel joins a blotch where they raised it (the drag hid it).

It reads frame t, its neighbours' frames and flows, and frame t's first-pass blotches only,
which every window and chunk of a film holding frame t computes alike: one result however
the film is run.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
from scipy import ndimage

from ..motion.dis import DisFlow
from ._grow import HYSTERESIS_LOW, rim_level
from ._morph import dilate
from ._motion import FilmMotion

ROUGH_GROW = 2  # px of rim filled roughly with the blotch (its soft edge)
DRAG = 4  # px around a blotch whose first flow is taken as dragged (DIS's start)
TAKE = 6  # px around a first-pass blotch within which the second look decides
# The window's interior reaches REACH px past the blotches (TAKE and the second look's
# growth); the scores and the checks see MARGIN px more of context. DIS (not MEND) sees
# at least MIN_SIDE px a side (DIS then keeps its preset's scales: a smaller image makes
# OpenCV choose other ones, and keep them for the instance's next images).
REACH = 10
FEATHER = 4
MARGIN = 12
MIN_SIDE = 64
MOVED = 0.25  # px a mended flow must move somewhere for its window to be scored again
EXPLAINED = 0.5  # share of a pixel's residual the repaired flows must take away
CHAIN = True  # the blotch checks run again in the windows (else: evidence only)
WHOLE = False  # the whole DRAG band takes its surroundings' flow (else where it fits better)
FREE = False  # the second look decides near its blotches, whatever the evidence did
MEND = True  # the flows mended from their surroundings (else estimated again by DIS)
SCORED = ("d", "d_any", "any_in", "spread", "zr", "res", "both", "n")

_local = threading.local()


def _dis() -> DisFlow:
    """This thread's DIS for windows (its own instance: an image under MIN_SIDE px would
    change an instance's scales for the whole frames after it). Given a flow of the
    image's size, OpenCV's DIS starts from it."""
    dis = getattr(_local, "dis", None)
    if dis is None:
        dis = _local.dis = DisFlow()
    return dis


def _span(start: int, stop: int, grow: int, size: int, side: int) -> slice:
    """[start - grow, stop + grow) within [0, size), widened to `side` where it fits."""
    lo, hi = max(start - grow, 0), min(stop + grow, size)
    short = side - (hi - lo)
    if short > 0:
        lo = max(lo - (short + 1) // 2, 0)
        hi = min(lo + side, size)
        lo = max(hi - side, 0)
    return slice(lo, hi)


def windows(blotch: np.ndarray, side: int = 0) -> list[tuple[tuple[slice, slice], tuple]]:
    """(interior, crop) per group of blotches within 2 REACH px of each other: the box
    REACH px around them, and that box with MARGIN px more, at least `side` px a side
    (none in a frame smaller than that)."""
    ny, nx = blotch.shape
    if ny < side or nx < side:
        return []
    labels, _ = ndimage.label(dilate(blotch, REACH))
    out = []
    for sy, sx in ndimage.find_objects(labels):
        inner = (slice(sy.start, sy.stop), slice(sx.start, sx.stop))
        crop = tuple(
            _span(sl.start, sl.stop, MARGIN, size, side) for sl, size in ((sy, ny), (sx, nx))
        )
        out.append((inner, crop))
    return out


def _nearest(bad: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Each pixel's nearest pixel outside `bad` (itself outside it); None if bad is empty
    or everything."""
    if not bad.any() or bad.all():
        return None
    return ndimage.distance_transform_edt(bad, return_indices=True)[1]


def _surroundings(flow: np.ndarray, bad: np.ndarray, near=False) -> np.ndarray:
    """flow with its `bad` pixels given their nearest good pixel's value (near: _nearest's,
    given)."""
    near = _nearest(bad) if near is False else near
    return flow.copy() if near is None else flow[near[0], near[1]]


def _window_flow(
    first: np.ndarray, a: np.ndarray, b: np.ndarray, crop: tuple, bad: np.ndarray
) -> tuple[np.ndarray, tuple[int, int]]:
    """The flow from a's window (uint8, the crop of a frame) to frame b (uint8, whole),
    started from `first` (the first flow on the crop) with its `bad` pixels replaced by
    their surroundings'; b's window is displaced by the start's median (whole pixels,
    within the frame). Returns the flow and the displacement (dy, dx)."""
    start = _surroundings(first, bad)
    good = start[~bad] if (~bad).any() else start.reshape(-1, 2)
    dx, dy = (int(np.rint(np.median(good[:, i]))) for i in (0, 1))
    (sy, sx), (h, w) = (crop[0], crop[1]), a.shape
    y0 = min(max(sy.start + dy, 0), b.shape[0] - h)
    x0 = min(max(sx.start + dx, 0), b.shape[1] - w)
    dy, dx = y0 - sy.start, x0 - sx.start
    shift = np.array([dx, dy], np.float32)
    init = np.ascontiguousarray(start - shift, np.float32)
    win = np.ascontiguousarray(b[y0 : y0 + h, x0 : x0 + w])
    flow = _dis().dis.calc(np.ascontiguousarray(a), win, init)
    return flow + shift, (dy, dx)


def _paste(flow: np.ndarray, part: np.ndarray, inner: tuple, crop: tuple) -> None:
    """flow[inner] takes part (the flow on crop), feathered over FEATHER px at the interior's
    edges that are not the frame's."""
    ny, nx = flow.shape[:2]
    (iy, ix), (cy, cx) = inner, crop
    ys = np.arange(iy.start, iy.stop, dtype=np.float32)[:, None]
    xs = np.arange(ix.start, ix.stop, dtype=np.float32)[None, :]
    big = np.float32(FEATHER)
    edge = [
        ys - iy.start + 1 if iy.start > 0 else big,
        iy.stop - ys if iy.stop < ny else big,
        xs - ix.start + 1 if ix.start > 0 else big,
        ix.stop - xs if ix.stop < nx else big,
    ]
    wgt = np.minimum(np.minimum(edge[0], edge[1]), np.minimum(edge[2], edge[3]))
    wgt = np.clip(wgt / big, 0.0, 1.0)[..., None]
    sub = part[iy.start - cy.start : iy.stop - cy.start, ix.start - cx.start : ix.stop - cx.start]
    flow[inner] = wgt * sub + (1.0 - wgt) * flow[inner]


def _shifted(box: tuple, dy: int, dx: int) -> tuple[slice, slice]:
    return (slice(box[0].start + dy, box[0].stop + dy), slice(box[1].start + dx, box[1].stop + dx))


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
        f = self.flow(t, s)
        back = self.warp(self.whole(s, t), t, s, "linear")
        return np.hypot(f[..., 0] + back[..., 0], f[..., 1] + back[..., 1])

    def loop_error(self, t: int, a: int, b: int) -> np.ndarray:
        fa, fb = self.flow(t, a), self.flow(t, b)
        fab = self.warp(self.whole(a, b), t, a, "linear")
        return np.hypot(
            fa[..., 0] + fab[..., 0] - fb[..., 0], fa[..., 1] + fab[..., 1] - fb[..., 1]
        )


def _repaired_flows(motion: FilmMotion, t: int, offs: list[int], blotch: np.ndarray, wins) -> dict:
    """Frame t's flows to its neighbours (and, at a film's ends, theirs back) with the
    windows' interiors estimated again on frame t with its blotches filled roughly."""
    import cv2

    hole = dilate(blotch, ROUGH_GROW)
    bad = dilate(blotch, DRAG)
    rough = motion.u8[t].copy()
    for _, crop in wins:
        h = hole[crop]
        u8, h8 = (np.ascontiguousarray(x, np.uint8) for x in (motion.u8[t][crop], h))
        filled = cv2.inpaint(u8, h8, 3, cv2.INPAINT_TELEA)
        rough[crop][h] = filled[h]
    one_sided = all(k > 0 for k in offs) or all(k < 0 for k in offs)
    flows = {}
    for k in offs:
        s = t + k
        ahead = motion.flow(t, s).copy()
        back = motion.flow(s, t).copy() if one_sided else None
        for inner, crop in wins:
            part, (dy, dx) = _window_flow(
                motion.flow(t, s)[crop], rough[crop], motion.u8[s], crop, bad[crop]
            )
            _paste(ahead, part, inner, crop)
            if back is not None:
                # the flow back from the neighbour's window that the blotch's window meets
                there = _shifted(crop, dy, dx)
                part, _ = _window_flow(
                    motion.flow(s, t)[there], motion.u8[s][there], rough, there, bad[crop]
                )
                _paste(back, part, _shifted(inner, dy, dx), there)
        flows[(t, s)] = ahead
        if back is not None:
            flows[(s, t)] = back
    return flows


def _grid(crop: tuple) -> tuple[np.ndarray, np.ndarray]:
    gy, gx = np.mgrid[crop[0], crop[1]]
    return gy.astype(np.float32), gx.astype(np.float32)


def _mend(
    first: np.ndarray, a: np.ndarray, b: np.ndarray, grid: tuple, hole: np.ndarray, bad, near
) -> np.ndarray:
    """The flow `first` on crop from frame a (its crop) to frame b (whole), mended: in the
    hole, the value of the nearest pixel outside `bad`; in the rest of `bad`, that value
    where it brings b's pixel nearer a's own (3x3 means of the absolute differences)."""
    import cv2

    filled = _surroundings(first, bad, near)
    gy, gx = grid

    def err(f: np.ndarray) -> np.ndarray:
        w = cv2.remap(
            b, gx + f[..., 0], gy + f[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        return cv2.blur(np.abs(a - w), (3, 3))

    use = bad if WHOLE else hole | (bad & (err(filled) < err(first)))
    return np.where(use[..., None], filled, first)


def _mended_flows(motion: FilmMotion, t: int, offs: list[int], blotch: np.ndarray, wins) -> dict:
    """Frame t's flows to its neighbours (and, at a film's ends, theirs back) mended around
    its blotches from their surroundings (_mend): no flow estimated again."""
    hole = dilate(blotch, ROUGH_GROW)
    bad = dilate(blotch, DRAG)
    G = motion.G
    nears = [_nearest(bad[crop]) for _, crop in wins]
    one_sided = all(k > 0 for k in offs) or all(k < 0 for k in offs)
    flows = {}
    for k in offs:
        s = t + k
        ahead = motion.flow(t, s).copy()
        back = motion.flow(s, t).copy() if one_sided else None
        for (_, crop), near in zip(wins, nears, strict=True):
            first = motion.flow(t, s)[crop]
            g = np.ascontiguousarray(G[t][crop])
            grid = _grid(crop)
            ahead[crop] = _mend(first, g, G[s], grid, hole[crop], bad[crop], near)
            if back is not None:
                # the neighbour's pixels that land on the blotch: its window displaced by
                # the flow's median there
                dx, dy = (int(np.rint(np.median(first[..., i]))) for i in (0, 1))
                (sy, sx), (h, w) = crop, first.shape[:2]
                y0 = min(max(sy.start + dy, 0), G.shape[1] - h)
                x0 = min(max(sx.start + dx, 0), G.shape[2] - w)
                there = (slice(y0, y0 + h), slice(x0, x0 + w))
                g = np.ascontiguousarray(G[s][there])
                args = (hole[crop], bad[crop], near)
                back[there] = _mend(motion.flow(s, t)[there], g, G[t], _grid(there), *args)
        flows[(t, s)] = ahead
        if back is not None:
            flows[(s, t)] = back
    return flows


def look_again(
    scores: dict,
    t: int,
    blotch: np.ndarray,
    marks: tuple[np.ndarray, np.ndarray],
    checks: tuple[Callable, Callable],
    threshold: float,
    frame_scores: Callable,
) -> np.ndarray:
    """Frame t's blotches after a second look around `blotch` (see the module text).

    scores: clpde.film.detect.film_scores' (with its "motion"); marks: the frame's
    scratches and their ghosts (never blotches); checks: blotches(G, scores, scratch,
    ghosts, size, level), the blotch checks on such scores for frame t
    (clpde.film.detect._frame_blotches), and evidence(scores), frame t's blotch evidence
    (clpde.film.detect.blotch_evidence); frame_scores: clpde.film.detect.frame_scores."""
    motion: FilmMotion = scores["motion"]
    T, ny, nx = motion.G.shape
    wins = windows(blotch, 0 if MEND else MIN_SIDE)
    radius = int(scores["radius"])
    offs = [k for k in range(-radius, radius + 1) if k != 0 and 0 <= t + k < T]
    if not wins or len(offs) < 2:
        return blotch
    flows = (_mended_flows if MEND else _repaired_flows)(motion, t, offs, blotch, wins)
    fixed = {"sigma": scores["sigma"][t], "zr_scale": scores["zr_scale"][t]}
    # the frame's own levels, which a window cannot measure: the rim's, from the first look
    scratch, ghosts = marks
    blotches, evidence = checks
    if CHAIN:
        level = rim_level(blotch, scratch | ghosts, scores["res"][t], scores["n"][t] > 0)
    second = np.zeros_like(blotch)
    # the blotch evidence with the first flows and with the mended ones
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
        if not CHAIN:
            continue
        # candidates only in the interior: the margin's flows are the first look's
        outside = np.ones(got["d"].shape, bool)
        outside[rel] = False
        for key in ("d", "d_any", "zr"):
            got[key][outside] = 0
        found = blotches(
            motion.G[:, crop[0], crop[1]], again, scratch[crop], ghosts[crop], ny * nx, level
        )
        second[inner] |= found[rel]
    # a first-pass pixel goes only where the mended flows took EXPLAINED of its evidence
    # away (a halo's residual was the flow's error; a faint rim's is the damage's and
    # stays); a pixel the first look did not take joins only where they raised its evidence
    # (the drag hid it: its residual, or the neighbours' spread that scales it): elsewhere
    # the first look saw the same evidence and decided
    # (the residual's: the evidence is 0 where a side lost its trust, which says nothing)
    explained = seen & (np.abs(res) < (1.0 - EXPLAINED) * np.abs(scores["res"][t]))
    revealed = after > before
    if not CHAIN:
        low = after > HYSTERESIS_LOW * threshold
        grown = dilate(blotch, TAKE, within=blotch | (low & revealed & ~(scratch | ghosts)))
        return (blotch & ~(explained & ~low)) | grown
    # the second look's regions that meet a first-pass blotch (one apart from them, within
    # TAKE px, is the flow's error the first look had no reason to see, or motion)
    parts, _ = ndimage.label(second)
    met = np.unique(parts[blotch])
    second = np.isin(parts, met[met > 0])
    labels, _ = ndimage.label(dilate(blotch, TAKE))
    confirmed = np.unique(labels[second])
    take = np.isin(labels, confirmed[confirmed > 0])
    if FREE:
        strong = np.abs(res) > threshold * scores["sigma"][t]
        return np.where(take, second | (blotch & strong), blotch)
    return np.where(take, (second & (blotch | revealed)) | (blotch & ~explained), blotch)
