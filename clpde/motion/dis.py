"""Dense motion from OpenCV's DIS optical flow (Kroeger et al. 2016), on the CPU.

Film restoration needs several flows per frame; on a 2-core CPU the device solver of
clpde.motion.flow takes seconds per 640x360 pair, DIS a few hundredths, and on the film
corpus of benchmarks/film_motion.py its compensated frames match at least as well. So the
film takes its motion from here; clpde.motion.optical_flow stays for masked flows and
tracking.

The flow's convention is `optical_flow`'s: ``frame1[y + v, x + u] ~ frame0[y, x]``.
DIS's patches are independent and its densification a fixed sum, so a flow depends only on
its two frames: the film's windows and chunks get the same flows bit for bit.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

# OpenCV 4.x's DIS presets, spelled out so that an OpenCV upgrade does not change the
# film's results silently: (finest scale, patch, stride, descent iterations, variational
# refinement iterations). The film uses PRESET (chosen in benchmarks/film_motion.py).
PRESETS = {
    "ultrafast": (2, 8, 4, 12, 0),
    "fast": (2, 8, 4, 16, 5),
    "medium": (1, 8, 3, 25, 5),
    # fast's patches and iterations down to half resolution (finest scale 1): on thin lines
    # (poles, wires) fast's quarter-resolution flow is 0.5 px off (p90), enough to show
    # them in the residual as scratches; this is 0.02 px, as medium, at half medium's time
    "fine": (1, 8, 4, 16, 5),
}
PRESET = "fine"


def _cv2():
    try:
        import cv2
    except ImportError as exc:  # pragma: no cover - the film extra installs it
        raise InputError(
            "film restoration needs OpenCV for its motion: pip install "
            "opencv-contrib-python-headless (or clpde[video])"
        ) from exc
    return cv2


def _dis(preset: str):
    cv2 = _cv2()
    finest, patch, stride, descent, refine = PRESETS[preset]
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    dis.setFinestScale(finest)
    dis.setPatchSize(patch)
    dis.setPatchStride(stride)
    dis.setGradientDescentIterations(descent)
    dis.setVariationalRefinementIterations(refine)
    dis.setVariationalRefinementAlpha(20.0)
    dis.setVariationalRefinementDelta(5.0)
    dis.setVariationalRefinementGamma(10.0)
    dis.setUseMeanNormalization(True)
    dis.setUseSpatialPropagation(True)
    return dis


def to_u8(grey: np.ndarray) -> np.ndarray:
    """A [0, 1] grey plane as the uint8 image DIS reads."""
    return np.ascontiguousarray(np.rint(np.clip(grey, 0.0, 1.0) * 255.0).astype(np.uint8))


class DisFlow:
    """One DIS instance, reused for every pair (its buffers are kept between calls)."""

    def __init__(self, preset: str = PRESET) -> None:
        self.cv2 = _cv2()
        self.preset = preset
        self.dis = _dis(preset)
        self._grid = None

    def flow(self, frame0: np.ndarray, frame1: np.ndarray) -> np.ndarray:
        """(H, W, 2) float32 flow from uint8 frame0 to uint8 frame1."""
        return self.dis.calc(frame0, frame1, None)

    def warp(self, image: np.ndarray, flow: np.ndarray, mode: str = "cubic") -> np.ndarray:
        """``image[y + v, x + u]``, coordinates clamped to the image; image (H, W) or
        (H, W, C) float32. mode: 'cubic' for pictures, 'linear' for flows and masks,
        'nearest'."""
        ny, nx = flow.shape[:2]
        if self._grid is None or self._grid[0].shape != (ny, nx):
            self._grid = np.meshgrid(
                np.arange(nx, dtype=np.float32), np.arange(ny, dtype=np.float32)
            )
        gx, gy = self._grid
        return self.remap(image, gx + flow[..., 0], gy + flow[..., 1], mode)

    def remap(self, image: np.ndarray, xs: np.ndarray, ys: np.ndarray, mode: str = "cubic"):
        """``image[ys, xs]`` interpolated, coordinates clamped to the image (`warp` with the
        coordinates x + u, y + v already formed: several images warped by one flow share
        them)."""
        cv2 = self.cv2
        modes = {"cubic": cv2.INTER_CUBIC, "linear": cv2.INTER_LINEAR, "nearest": cv2.INTER_NEAREST}
        return cv2.remap(image, xs, ys, modes[mode], borderMode=cv2.BORDER_REPLICATE)


def dis_flow(frame0: np.ndarray, frame1: np.ndarray) -> np.ndarray:
    """Dense optical flow from frame0 to frame1 by DIS: (H, W, 2) float32, ``optical_flow``'s
    convention.

    Parameters
    ----------
    frame0, frame1 : (rows, columns) array
        Grey frames: uint8, or floats in [0, 1].

    Returns
    -------
    ndarray
        (rows, columns, 2) float32: (u, v), u along columns.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.ndimage import gaussian_filter
    >>> scene = gaussian_filter(np.random.default_rng(0).random((80, 120)), 2)
    >>> a, b = scene[:, 10:90], scene[:, 12:92]  # b is a shifted 2 px left
    >>> f = dis_flow(a / scene.max(), b / scene.max())
    >>> bool(abs(np.median(f[..., 0]) + 2) < 0.2)
    True
    """
    a, b = np.asarray(frame0), np.asarray(frame1)
    if a.shape != b.shape or a.ndim != 2:
        raise InputError(f"dis_flow takes two grey frames of one shape, got {a.shape}, {b.shape}")
    if a.dtype != np.uint8:
        a, b = to_u8(a), to_u8(b)
    return DisFlow().flow(a, b)
