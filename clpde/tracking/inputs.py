"""The morphing tracker's inputs, checked: frames, the first mask, the user's feature maps,
and the frames scaled to [0, 1] as (T, C, H, W)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..imagedata import value_range


def check_frames(frames) -> list[np.ndarray]:
    """The frames as a list of (H, W) or (H, W, C) arrays of one size, or InputError."""
    if isinstance(frames, np.ndarray):
        if frames.ndim not in (3, 4) or (frames.ndim == 4 and frames.shape[-1] not in (3, 4)):
            raise InputError(
                f"frames must be a (T, H, W) grey or (T, H, W, 3) colour array, or a sequence "
                f"of frames, got an array of shape {frames.shape}"
            )
        items = list(frames)
    else:
        try:
            items = [np.asarray(f) for f in frames]
        except TypeError:
            raise InputError(
                "frames must be a (T, H, W) array or a sequence of 2-D arrays"
            ) from None
    if not items:
        raise InputError("frames is empty: give at least one frame")
    for k, f in enumerate(items):
        if not (f.ndim == 2 or (f.ndim == 3 and f.shape[-1] in (3, 4))):
            raise InputError(
                f"frame {k} has shape {f.shape}; every frame must be 2-D (grey) or (H, W, 3) colour"
            )
        if f.shape != items[0].shape:
            raise InputError(
                f"frame {k} is {f.shape[1]}x{f.shape[0]} but frame 0 is "
                f"{items[0].shape[1]}x{items[0].shape[0]}; all frames must have one size"
                + ("" if f.shape[:2] != items[0].shape[:2] else " and kind (grey or colour)")
            )
        if f.dtype == bool or not (
            np.issubdtype(f.dtype, np.integer) or np.issubdtype(f.dtype, np.floating)
        ):
            raise InputError(f"frame {k} has dtype {f.dtype}; expected integers or floats")
        if np.issubdtype(f.dtype, np.floating) and not np.isfinite(f).all():
            raise InputError(f"frame {k} contains NaN or infinite values")
    return items


def check_mask(mask, shape) -> np.ndarray:
    """The first mask as a boolean (H, W) array with an inside and an outside, or InputError."""
    mask = np.asarray(mask)
    if mask.ndim == 3 and mask.shape[-1] in (3, 4):  # a colour mask image: any nonzero colour
        mask = mask[..., :3].any(axis=-1)
    if mask.shape != shape:
        raise InputError(
            f"the first mask is {mask.shape[-1]}x{mask.shape[0]} (shape {mask.shape}) but the "
            f"frames are {shape[1]}x{shape[0]}; draw the mask on the first frame at its size"
        )
    mask = mask > 0 if mask.dtype != bool else mask
    if not mask.any():
        raise InputError("the first mask is empty: mark the object to follow in the first frame")
    if mask.all():
        raise InputError("the first mask covers the whole frame: leave the background unmarked")
    return mask


def user_features(features, frames: list[np.ndarray]) -> np.ndarray:
    """The user's feature maps as a (T, C, H, W) float64 array scaled to [0, 1] over the
    whole sequence (one scale for all frames keeps F2 - F1 meaningful)."""
    shape = frames[0].shape[:2]
    if callable(features):
        try:
            maps = [np.asarray(features(f), np.float64) for f in frames]
        except InputError:
            raise
        except Exception as exc:
            raise InputError(f"the features callable failed on a frame: {exc}") from exc
    else:
        maps = features
    try:
        stack = np.stack([np.asarray(m, np.float64) for m in maps])
    except ValueError:
        raise InputError("the feature maps must all have one shape") from None
    if len(stack) != len(frames):
        raise InputError(f"{len(stack)} feature maps for {len(frames)} frames: give one per frame")
    if stack.shape[1:3] == shape:
        stack = stack[:, np.newaxis] if stack.ndim == 3 else np.moveaxis(stack, -1, 1)
    if stack.ndim != 4 or stack.shape[2:] != shape:
        raise InputError(
            f"feature maps of shape {stack.shape[1:]} do not fit frames of {shape[1]}x{shape[0]}: "
            "give (H, W) or (H, W, C) per frame"
        )
    if not np.isfinite(stack).all():
        raise InputError("the feature maps contain NaN or infinite values")
    lo, hi = float(stack.min()), float(stack.max())
    return (stack - lo) / (hi - lo) if hi > lo else np.zeros_like(stack)


def scaled_frames(frames: list[np.ndarray], colour: bool) -> np.ndarray | ColourFrames:
    """(T, C, H, W) float64 in [0, 1], one scale for the whole sequence: every channel of
    colour frames with `colour` (a ColourFrames, read frame by frame), else their grey level
    (Rec. 601 luma)."""
    # stacked in the frames' own dtype (float64 where they differ), then converted once:
    # the same values as each frame converted
    same = all(f.dtype == frames[0].dtype for f in frames)
    stack = np.stack(frames, dtype=None if same else np.float64)
    if stack.ndim == 4 and colour:
        # the range of the values that ColourFrames converts: the extremes of the frames' own
        # dtype, converted (exactly) to float64 as the values are
        lo, hi = float(stack[..., :3].min()), float(stack[..., :3].max())
        value_range(lo, hi, "frames")  # refuses a span that overflows float64
        if hi > lo:
            return ColourFrames(stack, lo, hi)
        return np.zeros((len(stack), 3) + stack.shape[1:3])
    if stack.ndim == 4:
        stack = (stack.astype(np.float64)[..., :3] @ np.array([0.299, 0.587, 0.114]))[:, np.newaxis]
    else:
        stack = stack.astype(np.float64)[:, np.newaxis]
    lo, hi = float(stack.min()), float(stack.max())
    value_range(lo, hi, "frames")  # refuses a span that overflows float64
    if not hi > lo:
        return np.zeros_like(stack)
    # in place (a copy of the frames already): the same values as (stack - lo) / (hi - lo)
    stack -= lo
    stack /= hi - lo
    return stack


class ColourFrames:
    """The (T, 3, H, W) float64 colour frames in [0, 1] of scaled_frames, each frame
    converted from the clip's own dtype when it is read (the last few kept): the same values
    as the whole clip converted at once, (x - lo) / (hi - lo), without the clip's float64
    copy, 8 times uint8 footage's bytes, whose pages cost more to fault in than the tracker's
    reads of it (carphone, colour=True: 0.11-0.17 s a call against 2-9 ms; issue 35,
    docs/tracking.md). Reads by an index; anything else converts the whole clip."""

    ndim = 4
    dtype = np.dtype(np.float64)
    KEEP = 4  # frames kept converted: the tracker reads frames t - 1 and t, and frame 0

    def __init__(self, stack: np.ndarray, lo: float, hi: float):
        self._stack, self._lo, self._span = stack, lo, hi - lo
        self.shape = (len(stack), 3) + stack.shape[1:3]
        self._kept: dict[int, np.ndarray] = {}

    def __len__(self) -> int:
        return self.shape[0]

    def _convert(self, frames: np.ndarray) -> np.ndarray:
        # (the channels first and contiguous: interleaved, every read of a frame's (C, H, W)
        # strides through memory, and a mean over the channels is ten times slower)
        out = np.moveaxis(frames[..., :3], -1, -3).astype(np.float64, order="C")
        out -= self._lo
        out /= self._span
        return out

    def __getitem__(self, index):
        if not isinstance(index, (int, np.integer)):
            return np.asarray(self)[index]
        t = range(len(self))[index]  # (IndexError beyond the clip, as an array's)
        frame = self._kept.get(t)
        if frame is None:
            frame = self._convert(self._stack[t])
            if len(self._kept) >= self.KEEP:
                del self._kept[max((k for k in self._kept if k), key=lambda k: abs(k - t))]
            self._kept[t] = frame
        return frame

    def __array__(self, dtype=None, copy=None):
        whole = self._convert(self._stack)
        return whole if dtype is None else whole.astype(dtype)

    def mean(self, axis: int) -> np.ndarray:
        """The clip's mean over `axis` 1 (the channels), frame by frame: the same values as
        over the whole array (the channels added in turn either way)."""
        if axis != 1:
            return np.asarray(self).mean(axis=axis)
        return np.stack([self._convert(f).mean(axis=0) for f in self._stack])
