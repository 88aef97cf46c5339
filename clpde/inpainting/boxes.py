"""Boxes around the damage: each connected component of the mask, or cluster of nearby
components, is solved in its own box (its bounding box grown by the method's margin), so
that time and memory follow the damage rather than the image.

Boxes are built without a labelled copy of the whole mask: one pass marks the TILE x TILE
tiles that hold masked pixels, the tiles' 8-connected groups give the candidate clusters,
and boxes whose grown rectangles overlap are merged until none do. A box then holds every
masked pixel within its margin, and no masked pixel of another box: a method that reads at
most `margin` pixels around its omega gives the same result in its box as on the image.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

TILE = 16


def occupied_tiles(omega: np.ndarray, tile: int = TILE) -> np.ndarray:
    ny, nx = omega.shape
    starts = np.arange(0, nx, tile)
    rows = []
    for r0 in range(0, ny, tile):
        rows.append(np.logical_or.reduceat(omega[r0 : r0 + tile].any(axis=0), starts))
    return np.array(rows, bool).reshape(len(rows), len(starts))


def _bbox(omega, y0, y1, x0, x1):
    """Tight bounding box of omega's pixels inside a rectangle, or None."""
    part = omega[y0:y1, x0:x1]
    rows, cols = np.flatnonzero(part.any(axis=1)), np.flatnonzero(part.any(axis=0))
    if rows.size == 0:
        return None
    return y0 + rows[0], y0 + rows[-1] + 1, x0 + cols[0], x0 + cols[-1] + 1


def _grown(omega, tight, margin_of, align_of):
    """The tight box grown by its margin, its origin aligned, clipped to the image."""
    y0, y1, x0, x1 = tight
    crop = np.pad(omega[y0:y1, x0:x1], 1)  # one known pixel around, so distances are right
    margin, align = margin_of(crop), max(1, align_of(crop))
    ny, nx = omega.shape
    gy0, gx0 = max(0, y0 - margin), max(0, x0 - margin)
    gy0, gx0 = gy0 - gy0 % align, gx0 - gx0 % align
    return [gy0, min(ny, y1 + margin), gx0, min(nx, x1 + margin)], align


def boxes(omega: np.ndarray, margin_of, align_of=lambda crop: 1, tile: int = TILE):
    """[(y0, y1, x0, x1)] boxes covering omega, sorted; margin_of(crop) -> int or None (None:
    one box, the whole image)."""
    ny, nx = omega.shape
    occ = occupied_tiles(omega, tile)
    if not occ.any():
        return []
    labels, count = ndimage.label(occ, np.ones((3, 3), bool))
    found = []  # [tight box, grown box]
    for sl in ndimage.find_objects(labels):
        tight = _bbox(
            omega,
            sl[0].start * tile,
            min(ny, sl[0].stop * tile),
            sl[1].start * tile,
            min(nx, sl[1].stop * tile),
        )
        if tight is None:
            continue
        if margin_of(np.pad(omega[tight[0] : tight[1], tight[2] : tight[3]], 1)) is None:
            return [(0, ny, 0, nx)]
        found.append([list(tight), _grown(omega, tight, margin_of, align_of)[0]])
    i = 0
    while i < len(found):
        grown = np.array([g for _, g in found])
        a = grown[i]
        hit = (
            (grown[:, 0] < a[1])
            & (a[0] < grown[:, 1])
            & (grown[:, 2] < a[3])
            & (a[2] < grown[:, 3])
        )
        hit[i] = False
        if not hit.any():
            i += 1
            continue
        group = [i, *np.flatnonzero(hit)]
        tights = np.array([found[k][0] for k in group])
        tight = [tights[:, 0].min(), tights[:, 1].max(), tights[:, 2].min(), tights[:, 3].max()]
        box, align = _grown(omega, tight, margin_of, align_of)
        # the union keeps every grown rectangle of the group inside it
        box = [
            min(box[0], grown[group, 0].min()),
            max(box[1], grown[group, 1].max()),
            min(box[2], grown[group, 2].min()),
            max(box[3], grown[group, 3].max()),
        ]
        box[0] -= box[0] % align
        box[2] -= box[2] % align
        found = [f for k, f in enumerate(found) if k not in set(group)] + [[tight, box]]
        i = 0  # the grown union may now reach boxes checked before
    return sorted(tuple(int(v) for v in g) for _, g in found)
