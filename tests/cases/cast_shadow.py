"""A walker's cast shadow in a mask made by background subtraction (the truth of the real
footage clips, benchmarks/track_footage.py): the pixels that differ from the empty street
only because less light reaches it.

A cast shadow is not the object. Under the overcast sky of opencv-doc's vtest.avi it is
soft: it darkens the ground it falls on by a roughly constant factor, keeps the ground's
colour and texture, fades over several pixels, and lies on the ground at the feet. A pixel
of the mask is shadow where all of these hold (the classical tests: Horprasert et al.'s
brightness and chromaticity distortion, with the ratio's smoothness for the texture):

- its brightness against the background (the factor ``a`` that brings the background's
  colour closest to it) is in ``RATIO``: darker, but not black;
- what is left once the background is scaled by ``a`` is under ``CHROMA`` of the
  background's brightness: the same colour, only darker (jeans on a grey street, or a
  face, are not);
- the ratio of the frame to the background (both blurred over 1 px) changes by under
  ``SMOOTH`` a pixel: a penumbra, not an object's edge (the blurred rim of dark trousers on
  a grey street is as grey and as dark as a shadow, but its ratio jumps across 1-2 px);
- it is in the bottom ``GROUND`` of the mask's height: on the ground at the feet, not on
  the body.

The pieces of fewer than ``MIN_PIECE`` px are dropped (noise, not a shadow), and so are
slivers of the mask that only the shadow held up (under 2 px thick, next to it).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

RATIO = (0.6, 0.95)  # from 0.5 it took parts of vtest walker A's grey shoes (seen at 6x)
CHROMA = 0.05
SMOOTH = 0.1  # ratio per px; an overcast penumbra is about 0.05, a dark edge 0.3 and over
GROUND = 0.25
WARM = 0.005  # red less blue chromaticity: a shadow is not warmer than its ground
MIN_PIECE = 10


def _warmth(image: np.ndarray) -> np.ndarray:
    """Red less blue chromaticity (each over the pixel's sum): the yellow-red side up."""
    return (image[..., 0] - image[..., 2]) / np.maximum(image.sum(-1), 1e-12)


def cast_shadow(frame: np.ndarray, background: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The pixels of `mask` (H, W) that are the cast shadow on `background` (the empty
    scene) in `frame`, both (H, W, 3) in the same units (see the module's note)."""
    frame = np.asarray(frame, np.float64)
    background = np.asarray(background, np.float64)
    mask = np.asarray(mask, bool)
    rows = np.nonzero(mask.any(axis=1))[0]
    if rows.size == 0:
        return np.zeros_like(mask)
    power = np.maximum((background * background).sum(-1), 1e-12)
    a = (frame * background).sum(-1) / power
    chroma = np.linalg.norm(frame - a[..., None] * background, axis=-1) / np.sqrt(power)
    ratio = ndimage.gaussian_filter(frame.sum(-1), 1) / np.maximum(
        ndimage.gaussian_filter(background.sum(-1), 1), 1e-12
    )
    # Sobel's 3x3 sums weigh 8 px of difference: /8 gives the change per px
    change = np.hypot(ndimage.sobel(ratio, 0), ndimage.sobel(ratio, 1)) / 8
    top, bottom = rows[0], rows[-1]
    ground = np.arange(mask.shape[0])[:, None] >= bottom - GROUND * (bottom - top)
    shadow = mask & ground & (a > RATIO[0]) & (a < RATIO[1]) & (chroma < CHROMA)
    shadow &= change < SMOOTH
    shadow &= ndimage.gaussian_filter(_warmth(frame) - _warmth(background), 1) < WARM
    labels, count = ndimage.label(shadow)
    if count:
        shadow = (np.bincount(labels.ravel()) >= MIN_PIECE)[labels] & shadow
    return shadow


def without_cast_shadow(frame: np.ndarray, background: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """`mask` less its cast shadow, and less the slivers (under 2 px thick) next to the
    shadow that the shadow alone held to the mask."""
    mask = np.asarray(mask, bool)
    shadow = cast_shadow(frame, background, mask)
    out = mask & ~shadow
    sliver = out & ~ndimage.binary_opening(out) & ndimage.binary_dilation(shadow, iterations=2)
    return out & ~sliver
