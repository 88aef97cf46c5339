"""'Found again nearby' (issue 34): a flat dark template alone matches any dark place of
the neighbours, so a region is scene content only where it is found again with its rim
(clpde.film._regions._found_with_rim)."""

import numpy as np
from scipy.ndimage import gaussian_filter

from clpde.film import _regions as regions

NY, NX, SEARCH = 64, 80, 24


def _texture(rng, ny, nx):
    s = gaussian_filter(rng.random((ny, nx)), 2.0)
    return 0.4 + 0.4 * (s - s.min()) / (s.max() - s.min())


def _region(G, t, mask):
    """found_nearby's arguments for the region `mask` of frame t, as _spatially_damage
    passes them: its box grown by RIM_CLEAR[1] px, its pixels there, and the bar (a quarter
    of its contrast's mean square against its ring)."""
    pad = regions.RIM_CLEAR[1]
    ys, xs = np.nonzero(mask)
    y0, y1 = max(ys.min() - pad, 0), min(ys.max() + 1 + pad, NY)
    x0, x1 = max(xs.min() - pad, 0), min(xs.max() + 1 + pad, NX)
    own = mask[y0:y1, x0:x1]
    ring = regions._ring(own, own.astype(int), *regions.RIM_CLEAR)
    g = G[t, y0:y1, x0:x1]
    bar = float(np.mean((g[own] - np.median(g[ring])) ** 2)) / 4
    return ((y0, y1), (x0, x1)), own, bar


def test_flat_dark_dirt_beside_a_dark_flat_scene_region_is_not_found_again(rng):
    scene = _texture(rng, NY, NX)
    scene[18:26, 14:22] = 0.1  # a dark, flat part of the scene, in every frame
    G = np.stack([scene + 0.005 * rng.standard_normal((NY, NX)) for _ in range(3)])
    dirt = np.zeros((NY, NX), bool)
    dirt[20:25, 36:41] = True  # as dark and flat, in frame 1 only, 20 px away
    G[1][dirt] = 0.1
    G = G.astype(np.float32)
    box, own, bar = _region(G, 1, dirt)
    # by its values alone the dirt is found again (at the scene's dark region)...
    best = regions._best_place(G, 1, 0, box, own, SEARCH)
    assert best[0] <= bar and np.abs(best[1]).max() > 10
    # ...but not with its rim: it is damage
    assert not regions._found_nearby(G, 1, [0, 2], box, own, SEARCH, bar)


def test_a_dark_scene_region_moving_with_its_surroundings_is_found_again(rng):
    big = _texture(rng, NY + 20, NX + 20)
    big[30:37, 40:47] = 0.1  # a dark flat object, part of a panning scene
    G = np.stack(
        [
            big[3 * k : 3 * k + NY, 4 * k : 4 * k + NX] + 0.005 * rng.standard_normal((NY, NX))
            for k in range(3)
        ]
    ).astype(np.float32)
    obj = np.zeros((NY, NX), bool)
    obj[27:34, 36:43] = True  # where it lies in frame 1
    assert obj.sum() >= regions.RIM_SMALLEST
    box, own, bar = _region(G, 1, obj)
    assert regions._found_nearby(G, 1, [0, 2], box, own, SEARCH, bar)
