"""The frames before the morphing: grey levels equalised across the sequence, anisotropic
(Perona-Malik) smoothing, and the features on the device (the frames themselves, their
edge maps or their local contrast normalisation)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from skimage.exposure import equalize_hist

from ..fields import Field
from ..imagedata import value_range
from ..planar import bounded
from ..planar.flows import PlanarFlow, diffuse
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
        img = smooth_channels(img, options, runtime)
    return np.asarray(img, np.float64)


def smooth_channels(img: np.ndarray, options: TrackOptions, runtime: Runtime) -> np.ndarray:
    """The Perona-Malik pre-smoothing of each channel of (C, H, W) data, each scaled by its
    own range as `diffuse` scales a grey image: bit for bit `diffuse` channel by channel,
    in one flow over the C channels (planar.cl's steps act on each channel alone, with the
    same arithmetic per cell), so that colour=True pays one upload, one launch a step and
    one download a frame, not C of each (issue 35, docs/tracking.md)."""
    # The rational edge-stopping function: as anisotropic as the exponential one and
    # faster on PoCL, where exp() does not vectorise (docs/tracking.md).
    params = {"kappa": options.smooth_kappa, "edge": "rational"}
    steps = options.smooth_steps

    def by_channel():
        return np.stack(
            [
                diffuse(c, "perona-malik", steps=steps, device=runtime, progress=False, **params)
                for c in img
            ]
        )

    if len(img) == 1 or bounded.is_large(img):  # (large: diffuse goes a channel at a time)
        return by_channel()
    img = np.asarray(img, np.float64)
    ranges = [value_range(float(c.min()), float(c.max())) for c in img]
    # each channel in [0, 1] as to_kernel_layout puts a grey image: its minimum 0 and its
    # maximum 1 exactly (0 where flat), so that the flow's own scaling of the stack is
    # the identity
    scaled = np.stack([(c - lo) / scale for c, (lo, scale) in zip(img, ranges, strict=True)])
    flow = PlanarFlow(scaled, "perona-malik", channel_axis=0, device=runtime, **params)
    if flow.layout.offset != 0.0 or flow.layout.scale != 1.0:  # (a guard: never seen)
        return by_channel()
    out = flow.run(steps, progress=False).pair.cur.to_host()
    # back to each channel's range as ImageLayout.restore does
    return np.stack(
        [np.asarray(o, np.float64) * scale + lo for o, (lo, scale) in zip(out, ranges, strict=True)]
    )


def feature_field(image: np.ndarray, ls: LevelSet, options: TrackOptions) -> Field:
    """The (C, H, W) prepared frame's features on the level set's grid (ghosts filled):
    the frame itself, its gradient magnitude ('edges') or its local contrast ('contrast')."""
    grid = replace(ls.grid, nc=len(image))
    f = Field.from_host(grid, ls.pad(image))
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
