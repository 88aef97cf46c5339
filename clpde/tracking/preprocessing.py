"""The frames before the morphing: grey levels equalised across the sequence, anisotropic
(Perona-Malik) smoothing, and the features on the device (the frames themselves, their
edge maps or their local contrast normalisation)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from skimage.exposure import equalize_hist

from ..fields import Field
from ..planar.flows import diffuse
from ..runtime import Runtime
from .levelset import LevelSet
from .options import TrackOptions

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/levelset.cl", "tracking/features.cl")


def match_histogram(image: np.ndarray, reference: np.ndarray, levels: int = 4096) -> np.ndarray:
    """Histogram specification of data in [0, 1]: the grey-level map that gives `image` the
    grey-level distribution of `reference`, on `levels` quantisation levels (equal values
    stay equal)."""

    def quantise(a):
        return np.minimum((np.asarray(a) * levels).astype(np.int64), levels - 1)

    q = quantise(image)
    src = np.bincount(q.ravel(), minlength=levels).astype(np.float64)
    ref = np.bincount(quantise(reference).ravel(), minlength=levels).astype(np.float64)
    src_cdf = (np.cumsum(src) - 0.5 * src) / src.sum()  # each level at its mid-rank
    ref_cdf = (np.cumsum(ref) - 0.5 * ref) / ref.sum()
    present = ref > 0
    centres = (np.arange(levels) + 0.5) / levels
    mapping = np.interp(src_cdf, ref_cdf[present], centres[present])
    return mapping[q]


def prepare_frame(
    scaled: np.ndarray, index: int, options: TrackOptions, runtime: Runtime
) -> np.ndarray:
    """Frame `index` of the (T, C, H, W) scaled frames after histogram equalisation and
    anisotropic smoothing, as options say: (C, H, W) float64 in [0, 1]."""
    img = scaled[index]
    if options.equalize == "match" and index > 0:
        # Equalise the grey levels across the sequence: each frame gets the first
        # frame's histogram, as beta = F2 - F1 compares grey values directly.
        img = np.stack([match_histogram(c, r) for c, r in zip(img, scaled[0], strict=False)])
    elif options.equalize == "global":
        img = np.stack([equalize_hist(c) for c in img])
    if options.smooth and options.smooth_steps > 0:
        # The rational edge-stopping function: as anisotropic as the exponential one
        # and faster on PoCL, where exp() does not vectorise (docs/tracking.md).
        img = np.stack(
            [
                diffuse(
                    c,
                    "perona-malik",
                    steps=options.smooth_steps,
                    kappa=options.smooth_kappa,
                    edge="rational",
                    device=runtime,
                    progress=False,
                )
                for c in img
            ]
        )
    return np.asarray(img, np.float64)


def feature_field(image: np.ndarray, ls: LevelSet, options: TrackOptions) -> Field:
    """The (C, H, W) prepared frame's features on the level set's grid (ghosts filled):
    the frame itself, its gradient magnitude ('edges') or its local contrast ('contrast')."""
    grid = replace(ls.grid, nc=len(image))
    f = Field.from_host(grid, np.stack([ls.pad(c) for c in image]))
    if options.features not in ("edges", "contrast"):
        return f
    out = Field.empty(grid)
    if options.features == "edges":
        grid.launch(
            grid.kernel("tracking/levelset.cl", "levelset_gradient_magnitude"),
            f.data.data,
            out.data.data,
        )
    else:
        # Scaled by 1/4: normalised values of about +-2 become F2 - F1 of the
        # order of the [0, 1] grey levels, for which tol and dt are set.
        grid.launch(
            grid.kernel("tracking/features.cl", "features_local_contrast"),
            f.data.data,
            out.data.data,
            np.int32(options.contrast_radius),
            grid.scalar(options.contrast_eps**2),
            grid.scalar(0.25),
        )
    out.fill_ghosts()
    return out
