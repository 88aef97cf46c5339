"""Damage in a single scanned photograph (clpde.detect_defects with one image): spatial cues
only, as the module text of clpde.film.detect describes."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from scipy import ndimage
from skimage.morphology import black_tophat, disk, white_tophat

from ..runtime import get_runtime
from ._morph import dilate
from .lines import LineKernels, robust_scale, scratch_runs


def photo_damage(
    G: np.ndarray, speck_threshold: float, scratch_threshold: float, min_length: int, device
) -> tuple[np.ndarray, np.ndarray]:
    """(specks, scratches) of the grey image G (H, W): bool masks."""
    ny, nx = G.shape
    # the grain's level from the image minus its 5x5 median: film grain is correlated over
    # a pixel or two, which the finest-scale estimate of denoising misses
    sigma = max(robust_scale(G - ndimage.median_filter(G, size=5, mode="nearest")), 0.5 / 255)
    specks = np.zeros((ny, nx), bool)
    for rad in (1, 2, 4, 8):
        # at each scale, the components that stand out and fit in its disc: a speck, not
        # a stroke, an edge or a broad bump
        white = white_tophat(G, footprint=disk(rad))
        black = black_tophat(G, footprint=disk(rad))
        found = np.maximum(white, black) > speck_threshold * sigma
        labels, n = ndimage.label(found)
        keep = np.zeros(n + 1, bool)
        for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
            h, w = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
            area = int((labels[sl] == idx).sum())
            if not (
                max(h, w) <= 2 * rad + 1 and max(h, w) <= 3 * min(h, w) + 1 and area >= 0.3 * h * w
            ):
                continue
            # a speck steps off its surroundings; a smooth bump fades into them
            comp = labels == idx
            ring = dilate(comp, 2) & ~comp
            step = abs(float(G[comp].mean()) - float(np.median(G[ring])))
            keep[idx] = step > speck_threshold * sigma
        specks |= keep[labels]
    resid = G - ndimage.median_filter(G, size=(1, 9), mode="nearest")
    rt = get_runtime(device)
    kern = LineKernels(rt)
    zs = kern.line_score(
        cla.to_device(rt.queue, np.ascontiguousarray(resid, np.float32)), 3.0 * sigma
    )
    scratch = scratch_runs(zs, resid, sigma, scratch_threshold, min_length, thin=False)
    return specks, scratch
