"""The film detector's checks per candidate region (clpde.film.detect): does the motion
explain the region's surroundings (_ring_check), does it stand out against the
compensation error around it (_local_noise_check), is it found again nearby in the frame
before or after (_motion_check)? A region that fails one is not called a blotch: where the
motion is not trusted, nothing is damage (do no harm)."""

from __future__ import annotations

import numpy as np
from scipy import ndimage, signal, stats

from ._morph import dilate
from .lines import robust_scale

MATCH_RATIO = 0.1  # a displaced match this much better than the compensated one: motion
MOTION_TEXTURE = 3.0  # noise units of structure a region needs to be searched for
RING_LIMIT = 3.0  # noise units within which a blotch's surroundings match the neighbours
RING_TRUSTED = 0.6  # share of the ring with trusted motion on both sides
RING_QUIET = 0.5  # share of the ring that is trusted and matches
# px by which two displacements of a moving region may differ (integer placements of the
# search, and a little acceleration) and still be one velocity
STEADY = 2.0
# the ring (px out) a region's values are compared with by the spatial test: past the soft
# rim that a blotch's evidence stops short of (its darkened or brightened pixels would
# widen the ring's range towards the blotch's own values)
RIM_CLEAR = (2, 5)
# px a region needs for its rim to be asked too where it is found again nearby
# (_found_with_rim): on the calibration half the scene regions the rim test alone would
# have called dirt were all 4-7 px, the dirt it recovered 15-111 px
RIM_SMALLEST = 8
EDGE = 2  # px from the frame's border within which the warp's stencil leaves the frame
EDGE_SPREAD = 2.0  # pixels the flow may spread around a blotch (more: a motion boundary)
TAIL_REACH = 8  # px around a region whose residuals are its own surroundings' (tail check)
# The deviation of a pixel's residual against the median of its neighbours, in units of the
# grain's: the pixel's grain and the median's (of 2-4 neighbours with grain of their own).
RESIDUAL_UNITS = 1.16


def _components(labels: np.ndarray, pad: int):
    """Each labelled component: (label, window: its box grown by pad px within the frame,
    its own pixels in the window)."""
    ny, nx = labels.shape
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        win = (
            slice(max(sl[0].start - pad, 0), min(sl[0].stop + pad, ny)),
            slice(max(sl[1].start - pad, 0), min(sl[1].stop + pad, nx)),
        )
        yield idx, win, labels[win] == idx


def _kept(mask: np.ndarray, pad: int, test) -> np.ndarray:
    """The components of mask for which test(win, own, labels_win) holds: win, the
    component's box grown by pad px; own, its pixels there; labels_win, every component's
    labels there (a ring must leave the others out)."""
    labels, _ = ndimage.label(mask)
    keep = np.zeros(labels.max() + 1, bool)
    for idx, win, own in _components(labels, pad):
        keep[idx] = test(win, own, labels[win])
    return keep[labels]


def _ring(own: np.ndarray, labels_win: np.ndarray, inner: int, outer: int) -> np.ndarray:
    """The pixels inner+1 to outer px from `own` that belong to no component."""
    ring = dilate(own, outer)
    ring &= ~dilate(own, inner)
    return ring & (labels_win == 0)


def _core(own: np.ndarray) -> np.ndarray:
    """A region's core: its pixels 2 px in from its edge, or 1, where 4 px would not remain
    (the whole region where not even those would)."""
    core = own
    for _ in range(2):
        inner = ndimage.binary_erosion(core)
        if inner.sum() < 4:
            break
        core = inner
    return core


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
    comp_mask: np.ndarray,
    G: np.ndarray,
    t: int,
    resid: np.ndarray,
    search: int,
    sigma: float,
    threshold: float,
) -> np.ndarray:
    """Drop the components of comp_mask (frame t) that are found in the frame before or
    after: a moving object the flow missed is found again nearby (or in place, where the
    flow wandered), a blotch is not.

    A component with structure of its own (MOTION_TEXTURE noise units), with a ring of two
    pixels for context, is matched within `search` pixels of its place in each neighbour;
    it moved if, at the best place in either, its own pixels differ by less than
    MATCH_RATIO of their difference from the compensated neighbours (medians of squares).
    A flat one (dirt is mostly flat) moved if it is found on both sides at places one
    steady velocity explains (_moves_steadily); flat is judged on the component's core (2
    px in from its edge, or 1, where 4 px remain), as a soft rim blends the dirt into the
    scene and gives it the scene's texture (on the calibration half, the flat test on the
    whole component sent about 400 px of dirt at the film's ends to the spatial test, which
    failed them). Within EDGE px of the frame's border
    (content enters and leaves there), and at a film's first and last frames (one side
    only) for a component with structure, it is kept only where the frame's own
    surroundings say damage at the blotch `threshold` (_spatially_damage). Flat ones at the
    ends keep ROD's say: asking the spatial test of them too cost 4% of the calibration
    half's blotch recall (0.601 -> 0.559) and no frame there got better."""
    T, ny, nx = G.shape

    def damage(win, own, labels_win) -> bool:
        (y0, y1), (x0, x1) = (win[0].start, win[0].stop), (win[1].start, win[1].stop)
        region = dilate(own, 2)
        r2 = resid[y0:y1, x0:x1] ** 2
        # medians: a component may carry some clean pixels or a trail beside the object
        e_own = float(np.median(r2[own]))
        templ = np.ascontiguousarray(G[t, y0:y1, x0:x1])
        th, tw = templ.shape
        ring = _ring(own, labels_win, 1, 4)
        ys, xs = np.nonzero(own)
        edge = min(ys.min() + y0, xs.min() + x0, ny - 1 - ys.max() - y0, nx - 1 - xs.max() - x0)
        # the dirt's own texture: its core (a soft rim carries the scene's)
        flat = robust_scale(templ[_core(own)]) < MOTION_TEXTURE * sigma
        if (not 0 < t < T - 1 and not flat) or edge < EDGE:
            # at the frame's edge content enters and leaves (the flow there is extrapolated),
            # and a film's ends have one side only: ROD cannot tell an object the flow
            # missed from damage (a region with structure may be either); the frame's own
            # surroundings decide (_spatially_damage, at the blotch threshold)
            side = float(np.median(resid[win][own]))
            beyond = _ring(own, labels_win, *RIM_CLEAR)
            return bool(beyond.sum() >= 4) and _spatially_damage(
                G, t, win, own, beyond, side, threshold * sigma, search
            )
        # a flat spot (dirt is mostly flat) matches any dark or bright place of the
        # neighbours: it is an object only where it is found again on both sides at places
        # one steady velocity explains (a flat object the flow did not follow)
        if flat:
            if ring.sum() < 4:
                return True
            g = templ[own]
            bar = float(np.mean((g - np.median(templ[ring])) ** 2)) / 4
            return not _moves_steadily(G, t, ((y0, y1), (x0, x1)), own, search, bar)
        found = []  # the median squared difference at the best place in each neighbour
        for s in (t - 1, t + 1):
            if not 0 <= s < T:
                continue
            wy0, wy1 = max(y0 - search, 0), min(y1 + search, ny)
            wx0, wx1 = max(x0 - search, 0), min(x1 + search, nx)
            area = np.ascontiguousarray(G[s, wy0:wy1, wx0:wx1])
            if area.shape[0] < th or area.shape[1] < tw:
                continue
            res = _masked_ssd(area, templ, region.astype(np.float64))
            my, mx = np.unravel_index(int(np.argmin(res)), res.shape)
            found.append(float(np.median((templ - area[my : my + th, mx : mx + tw])[own] ** 2)))
        # found in either neighbour, at any displacement (zero included: a flow that
        # wandered off a still region warps the wrong pixels onto it): not damage
        return not any(f < MATCH_RATIO * e_own for f in found)

    return _kept(comp_mask, RIM_CLEAR[1], damage)


def _ring_check(
    mask: np.ndarray,
    both: np.ndarray,
    res: np.ndarray,
    sigma: float,
    flows: np.ndarray,
    bridge: np.ndarray | None = None,
) -> np.ndarray:
    """Keep the components of mask whose surroundings the motion explains: on a ring 2-4
    px out, most pixels have a trusted neighbour on each side and the frame matches them
    (median residual within RING_LIMIT noise units). A blotch lies on a scene the flow
    follows; an object the flow missed, an occlusion or a deforming region does not, and
    there nothing is called a blotch (do no harm). Nor next to a motion boundary: where the
    flows to both nearest neighbours spread by more than EDGE_SPREAD px over a ring 3-6
    px out, an occluded or revealed region would pass for damage (at a film's ends
    nothing else tells them apart); both flows, as damage disturbs the flow around it.
    A large blotch disturbs both (both are estimated from its frame): `bridge`, the flow
    between the two nearest neighbours (at a film's ends both on its one side; None with
    one neighbour), carries none of the frame's damage and has the scene's own boundaries;
    its spread on the ring (taken where the flow to the nearest neighbour puts it) counts
    as a third."""

    def explained(win, own, labels_win) -> bool:
        ring = _ring(own, labels_win, 1, 4)
        if ring.sum() < 4:
            return False
        trusted = both[win][ring]
        quiet = np.abs(res[win][ring]) <= RING_LIMIT * sigma
        if not (trusted.mean() >= RING_TRUSTED and (trusted & quiet).mean() >= RING_QUIET):
            return False
        outer = dilate(own, 6) & ~dilate(own, 2)
        # a motion boundary is the frame's own: both flows show it; a blotch disturbs the
        # flows around it too, but rarely both (the least spread decides)
        spread = min(_spread(f) for f in flows[(slice(None), *win)][:, outer])
        if bridge is not None and spread > EDGE_SPREAD:
            spread = min(spread, _spread(_bridged(bridge, flows[0], win, outer)))
        return spread <= EDGE_SPREAD

    return _kept(mask, 7, explained)


def _spread(f: np.ndarray) -> float:
    """The larger of a set of flow vectors' (n, 2) 5-95% ranges in x and y."""
    lo, hi = np.percentile(f, [5, 95], axis=0)
    return float((hi - lo).max())


def _bridged(bridge: np.ndarray, back: np.ndarray, win, where: np.ndarray) -> np.ndarray:
    """The bridge flow's vectors (n, 2) at the window's pixels `where`, moved into the
    nearest neighbour's frame by the median of the flow `back` to it there (one shift: the
    flow to it is the damaged frame's, sound on the ring's majority)."""
    ny, nx = bridge.shape[:2]
    ys, xs = np.nonzero(where)
    dx, dy = np.median(back[win][where], axis=0)
    yy = np.clip(ys + win[0].start + int(round(float(dy))), 0, ny - 1)
    xx = np.clip(xs + win[1].start + int(round(float(dx))), 0, nx - 1)
    return bridge[yy, xx]


def _local_noise_check(
    mask: np.ndarray, a: np.ndarray, res: np.ndarray, sigma: float, threshold: float
) -> np.ndarray:
    """Keep the components of mask that stand out against the compensation error of their
    own surroundings: the peak evidence, divided by the ring's (2-3 px out) residual level
    in units of the grain's (the residual against the neighbours' median has a deviation
    of RESIDUAL_UNITS sigma under grain alone; more where the flow is off), must still
    reach the threshold. The level is read from the ring's residuals of the other sign
    where that is lower (at least 4 of them): a faint blotch's own rim, one-signed, lies
    in the ring of its first-pass core and is no compensation error, which comes with
    both signs. Flow and warp errors come in clusters, and a small region of them
    lies among others; a blotch lies on a scene the neighbours compensate."""

    def stands_out(win, own, labels_win) -> bool:
        ring = _ring(own, labels_win, 1, 3)
        if not ring.any():
            return False
        r = res[win]
        side = np.sign(np.median(r[own]))
        other = r[ring][np.sign(r[ring]) == -side]
        level = 1.4826 * float(np.median(np.abs(r[ring])))
        if other.size >= 4:
            level = min(level, 1.4826 * float(np.median(np.abs(other))))
        local = max(1.0, level / (RESIDUAL_UNITS * sigma))
        return float(a[win][own].max()) >= threshold * local

    return _kept(mask, 4, stands_out)


def _tail_check(
    mask: np.ndarray, busy: np.ndarray, res: np.ndarray, area: float, valid: np.ndarray
) -> np.ndarray:
    """Keep the components of mask that the residual of their own surroundings does not
    explain (heavy tails included: foliage, motion blur, a codec's blocks): with f the share
    of the surroundings (3 to TAIL_REACH px out, outside `busy`, where `valid`) whose
    |residual| reaches the region's median |residual|, and m = n / area the region's
    independent cells (area: the grain's correlation area), the chance that at least half
    of m such cells reach it, P(Bin(m, f) >= m / 2), must stay below n / (H W): at most one
    region of n pixels per frame expected from the surroundings alone. Nothing fitted: the
    region is measured against its own neighbourhood's distribution, and the frame's count
    of places sets the bar (multiple testing). f is estimated from the N surrounding pixels,
    k of which reach, as (k + 1/2) / (N + 1) (Jeffreys): a few hundred pixels none of which
    reach do not show that a share of 0 does (their chance of all missing a share of 1/N is
    about 1/e), so a region of one or two cells cannot rise above its surroundings at the
    frame's bar. On the calibration half it takes the small false alarms on textured,
    motion-blurred foliage that made frames worse than their input
    (benchmarks/film_worse.py: tree b frame 5's 12 and 8 px, on white flowers)."""

    def unexplained(win, own, labels_win) -> bool:
        around = dilate(own, TAIL_REACH)
        around &= ~dilate(own, 2) & ~busy[win] & valid[win]
        if not around.any():
            return True
        r = np.abs(res[win])
        count = int(own.sum())
        reach = int((r[around] >= np.median(r[own])).sum())
        share = (reach + 0.5) / (int(around.sum()) + 1.0)
        cells = max(1, round(count / area))
        chance = float(stats.binom.sf(np.ceil(cells / 2) - 1, cells, share))
        return chance <= count / mask.size

    return _kept(mask, TAIL_REACH, unexplained)


def _best_window(G: np.ndarray, t: int, s: int, box, weight: np.ndarray, search: int):
    """Frame t's window `box` sought in frame s within `search` px, each pixel's squared
    difference weighing `weight` (_masked_ssd): (the weighted sum at the best placement,
    the displacement (dy, dx), frame s's pixels there); None if the search window does not
    fit."""
    T, ny, nx = G.shape
    (y0, y1), (x0, x1) = box
    templ = np.ascontiguousarray(G[t, y0:y1, x0:x1])
    th, tw = templ.shape
    wy0, wy1 = max(y0 - search, 0), min(y1 + search, ny)
    wx0, wx1 = max(x0 - search, 0), min(x1 + search, nx)
    win = np.ascontiguousarray(G[s, wy0:wy1, wx0:wx1])
    if win.shape[0] < th or win.shape[1] < tw:
        return None
    ssd = _masked_ssd(win, templ, weight)
    my, mx = np.unravel_index(int(np.argmin(ssd)), ssd.shape)
    shift = np.array([my + wy0 - y0, mx + wx0 - x0], float)
    return float(ssd[my, mx]), shift, win[my : my + th, mx : mx + tw]


def _best_place(G: np.ndarray, t: int, s: int, box, own: np.ndarray, search: int):
    """The best placement, within `search` px, of frame t's pixels `own` (in the window
    box) in frame s, by their values alone (no context: a flat region is sought as such):
    (the mean squared difference there, the displacement (dy, dx)); None if the window
    does not fit."""
    found = _best_window(G, t, s, box, own.astype(np.float64), search)
    return None if found is None else (found[0] / own.sum(), found[1])


def _found_nearby(G: np.ndarray, t: int, frames, box, own: np.ndarray, search: int, bar: float):
    """Whether the pixels `own` of frame t are found again (_best_place: mean square below
    `bar`), at any displacement, zero included, in one of `frames`."""
    for s in frames:
        best = _best_place(G, t, s, box, own, search)
        if best is None or best[0] > bar:
            continue
        # a region of a few px is judged by its values alone: on textured, deforming
        # foliage (tree.avi) its rim is found nowhere, dirt or not
        if own.sum() < RIM_SMALLEST or _found_with_rim(G, t, s, box, own, search, bar):
            return True
    return False


def _found_with_rim(G: np.ndarray, t: int, s: int, box, own: np.ndarray, search: int, bar: float):
    """Whether frame t's pixels `own` are found in frame s together with their rim (the
    pixels up to RIM_CLEAR[1] - 1 px out, each part weighing half): at the best such place
    within `search` px, the mean square on the region and that on its rim both below
    `bar`. A flat dark or bright template alone matches any dark or bright place of the
    scene (on the calibration half, strong dirt 14 and 31 noise units outside its ring was
    dropped so on carphone); scene content moves with its surroundings and is found with
    them, dirt lies on a scene it does not belong to."""
    rim = dilate(own, RIM_CLEAR[1] - 1) & ~own
    if not rim.any():
        return True
    found = _best_window(G, t, s, box, own / own.sum() + rim / rim.sum(), search)
    if found is None:
        return True
    (y0, y1), (x0, x1) = box
    diff = (found[2] - G[t, y0:y1, x0:x1]) ** 2
    return bool(diff[own].mean() <= bar and diff[rim].mean() <= bar)


def _moves_steadily(G: np.ndarray, t: int, box, own: np.ndarray, search: int, bar: float):
    """Whether a flat region of frame t is an object moving steadily: found again
    (_best_place: mean square below `bar`) in the nearest frame each side (at a film's ends
    the two nearest on its one side) at displacements that one velocity explains (within
    STEADY px), other than standing still. Dirt is found so only by chance: a dark or
    bright place of the scene near it lies at one displacement in both frames, and one
    velocity explains that only at zero; and a region found in place on both sides, the
    scene moving under it, is fixed to the film (a scratch, dust on the scanner's glass)."""
    T = len(G)
    frames = [s for s in (t - 1, t + 1, t - 2, t + 2) if 0 <= s < T]
    sides = [s for s in frames if abs(s - t) == 1]
    pair = sides if len(sides) == 2 else frames[:2]
    velocities = []
    for s in pair:
        best = _best_place(G, t, s, box, own, search)
        if best is None or best[0] > bar:
            return False
        velocities.append(best[1] / (s - t))
    if len(velocities) < 2:
        return bool(velocities)
    # the farther frame's displacement against the one the nearer frame's velocity predicts
    gap = np.abs(velocities[0] - velocities[1]) * max(abs(s - t) for s in pair)
    # found in place on both sides while the scene moves under it (else the flow had
    # followed it): fixed to the film, as a scratch or dust on the scanner's glass is
    still = np.abs(velocities[0]).max() < 1
    return bool(gap.max() <= STEADY) and not still


def _spatial_blotches(
    G: np.ndarray,
    t: int,
    z: np.ndarray,
    sign: np.ndarray,
    threshold: float,
    low: float,
    smallest: float,
    sigma: float,
    search: int,
    taken: np.ndarray,
) -> np.ndarray:
    """Blotches where the motion is not trusted on both sides (occlusion, a failed flow
    loop, non-rigid motion, a film's ends): z, the distance of each pixel outside the range
    of ALL its neighbours' compensated values (trusted or not, wherever the match lies
    inside), in noise units, and the frame's own surroundings must both say damage:

    - temporal: the region (connected z > low, outside `taken`) has a median z of at least
      `threshold` (more than half its pixels, not a peak: one-sided evidence is weaker);
    - spatial: more than half its core lies outside the range (5th to 95th percentile) of
      its ring (RIM_CLEAR px out) by `threshold` noise units, on the side of its temporal
      sign, and more than half its pixels outside it at all (_spatially_damage): an
      outlier against its own surroundings, as dirt is and an object's part seldom is;
    - not found again: its values alone are not found within `search` px, at any
      displacement, in the nearest frame each side (at a film's ends the two nearest on
      its one side) closer than halfway between them and their ring's level (the nearer
      class: mean square below a quarter of their contrast's): a moving object is there,
      dirt is not.

    Returns the bool mask of the regions kept (at least `smallest` px)."""

    def damage(win, own, labels_win) -> bool:
        if own.sum() < smallest or np.median(z[win][own]) < threshold:
            return False
        ring = _ring(own, labels_win, *RIM_CLEAR) & ~taken[win]
        if ring.sum() < 4:
            return False
        side = np.median(sign[win][own])
        return _spatially_damage(G, t, win, own, ring, side, threshold * sigma, search)

    return _kept((z > low) & ~taken, RIM_CLEAR[1], damage)


def _spatially_damage(G: np.ndarray, t: int, win, own, ring, side: float, bar: float, search: int):
    """Whether a region (pixels `own` of frame t's window `win`, of temporal sign `side`)
    is damage by the frame's own surroundings: more than half its core (_core) lies
    outside the range (5th to 95th percentile) of its ring by `bar`, on that side, and
    more than half the whole region outside it at all; and its values alone are not found
    again within `search` px in the nearest frame each side (at a film's ends the two
    nearest on its one side) closer than halfway to their ring's level (a mean square below
    a quarter of their contrast's: the nearer class).

    The core, as a soft rim blends dirt into the scene: its pixels lie between the two, so
    a large blotch's median over all its pixels falls short of the bar (on the calibration
    half a 113 px blotch 82 levels dark at tree b's last frame: 5.7 noise units outside its
    ring over the region, 10.3 on its core, against 7). A blend still lies beyond the
    ring's range; the rule that most of the region does keeps scene regions with an
    outlying ridge out (carphone a frame 10: 146 px, its 14 px core 4.2 units out against
    the low-level path's 3.5, the region's median inside the range)."""
    T = len(G)
    g = G[t][win]
    lo, hi = np.percentile(g[ring], [5, 95])
    outside = (lo - g) if side < 0 else (g - hi)
    if np.median(outside[_core(own)]) < bar or np.median(outside[own]) <= 0:
        return False
    near = [s for s in (t - 1, t + 1) if 0 <= s < T]
    if len(near) < 2:
        near += [s for s in (t - 2, t + 2) if 0 <= s < T]
    contrast = float(np.mean((g[own] - np.median(g[ring])) ** 2))
    box = ((win[0].start, win[0].stop), (win[1].start, win[1].stop))
    return not _found_nearby(G, t, near, box, own, search, contrast / 4)
