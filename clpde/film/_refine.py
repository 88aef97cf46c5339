"""A second look around the blotches the first detection pass found (issue 34).

A blotch drags its own frame's optical flow (DIS cannot be told to ignore pixels), so the
compensated neighbours are misaligned around it: the residual flags a halo next to the
damage, and the same disturbance hides some of its pixels. The flows of the frames with
blotches are estimated again on those frames with the blotches filled in roughly (the
fill's own remedy, `rough`), and the kinds found with them replace the first pass's
within `REFINE_GROW` pixels of a first-pass blotch only. The flows between frames without
blotches are the first pass's (the same two frames give the same flow).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import ndimage

from ..motion.dis import to_u8
from ._morph import dilate
from ._motion import FilmMotion, map_frames

# How far from a first-pass blotch the second pass's kinds are taken (pixels): the halo
# lies within 3 px of the damage; the flow's disturbance reaches a little further.
REFINE_GROW = 6
# The rough fill covers the blotch and its rim (the grown region's soft edge).
ROUGH_GROW = 2


def rough(G: np.ndarray, m: np.ndarray) -> np.ndarray:
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


def refine_blotches(
    G: np.ndarray,
    kinds: np.ndarray,
    first: FilmMotion,
    rescore: Callable[[FilmMotion], tuple[np.ndarray, np.ndarray]],
    blotch: int,
) -> np.ndarray:
    """kinds (T, H, W) with the kinds near its `blotch` pixels found again by
    rescore(motion) (the kinds, and where the residual is strong), motion's flows
    estimated on the frames with those blotches filled roughly (reusing `first`'s flows
    between frames without any)."""
    found = kinds == blotch
    hit = {t for t in range(len(G)) if found[t].any()}
    if not hit:
        return kinds
    holes = np.stack([dilate(f, ROUGH_GROW) if f.any() else f for f in found])
    motion = FilmMotion(G, rough(G, holes))
    for key, flow in list(first._kept.items()):
        if len(key) == 2 and not hit.intersection(key):
            motion._kept[key] = flow
    again, strong = rescore(motion)
    out = kinds.copy()
    for t in hit:
        # a first-pass blotch the second pass finds nothing of keeps its first-pass kinds
        # (the second pass's flows may miss it for other reasons); one it confirms takes
        # the second pass's kinds around it
        labels, _ = ndimage.label(dilate(found[t], REFINE_GROW))
        confirmed = np.unique(labels[again[t] == blotch])
        take = np.isin(labels, confirmed[confirmed > 0])
        out[t][take] = again[t][take]
        # a first-pass pixel whose residual stays beyond the low level with the repaired
        # flows stays: a halo's residual was the flow's error, and goes with it
        keep = take & found[t] & strong[t] & (out[t] == 0)
        out[t][keep] = blotch
    return out
