"""A film restored through a sliding window of frames: memory bounded whatever its length.

The film's frames are cut into blocks of ``block`` frames on a fixed grid. Each block is
restored from a window that adds the temporal context the work needs on both sides:

- filling frame t reads the masks and frames of t - fill_radius .. t + fill_radius;
- detecting the mask of frame t reads the frames of t - detect_radius .. t + detect_radius;

so a block [s, e) reads the frames [s - R, e + R) with R = fill_radius + detect_radius
(clipped to the film). Only one window of frames is held at a time, read from the decoder
as it goes and written out in order.

The grid is the same however the film is run: in one process here, or in chunks of whole
blocks on Dask's workers (clpde.film.chunks), whose windows are the same arrays given to the
same functions; so a chunked run gives the frames of one process, bit for bit.

The per-window work is a :class:`WindowWork`: a detector (frames -> masks, or masks and
kinds) and a filler ((frames, masks) -> frames, given the detector's kinds too where it
says it takes them), both plain picklable callables, so the window machinery can be run
and tested with any of them.
"""

from __future__ import annotations

import functools
import inspect
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..imagedata import grow_mask
from ._motion import keep_flows
from .detect import detect_defects
from .fill import inpaint_video

KEEP = 3.0  # inpaint_video's keep for detected masks (noise units)
DEFAULT_BLOCK = 32  # frames restored per window: the context re-read per block is 2R/block
# flows per frame of the context two windows share, kept for the next window (the detector
# estimates 6 per frame: to the 4 neighbours, and 2 loops through them)
FLOWS_KEPT = 6


@dataclass(frozen=True)
class Block:
    """A block of frames [start, stop) and the window [first, last) it is restored from."""

    first: int
    start: int
    stop: int
    last: int


def plan_blocks(
    count: int, block: int, context: int, span: tuple[int, int] | None = None
) -> list[Block]:
    """The fixed grid of blocks over a film of `count` frames, or over a section of it.

    Parameters
    ----------
    count : int
        Frames in the film.
    block : int
        Frames restored per window (the last block may be shorter).
    context : int
        Frames of context read on each side of a block (clipped to the film, not to the
        section: a frame's result depends on its own window only, so a section's frames
        come out as in a run of the whole film).
    span : (int, int), optional
        Restore only the frames [start, stop) (default: all).

    Returns
    -------
    list of Block
        In frame order, covering every frame once.

    Raises
    ------
    InputError
        If `block` is below 1, `context` below 0, or `span` not within the film.

    Examples
    --------
    >>> plan_blocks(5, 2, 1)
    [Block(first=0, start=0, stop=2, last=3), Block(first=1, start=2, stop=4, last=5), \
Block(first=3, start=4, stop=5, last=5)]
    """
    if isinstance(block, bool) or int(block) != block or block < 1:
        raise InputError(f"the block must be a whole number of frames >= 1, not {block!r}")
    if context < 0:
        raise InputError(f"the temporal context must be >= 0 frames, not {context!r}")
    start, stop = (0, count) if span is None else span
    if span is not None and not 0 <= start < stop <= count:
        raise InputError(f"frames {start}..{stop - 1} are not within the film's 0..{count - 1}")
    return [
        Block(
            max(0, s - context), s, min(stop, s + block), min(count, min(stop, s + block) + context)
        )
        for s in range(start, stop, block)
    ]


def grow_masks(masks: np.ndarray, pixels: float) -> np.ndarray:
    """Grow boolean masks (T, H, W) or (H, W) by `pixels` in the image plane (a disc).

    Parameters
    ----------
    masks : ndarray of bool
        The masks.
    pixels : float
        The growth radius in pixels (0: unchanged).

    Returns
    -------
    ndarray of bool
        Each pixel within `pixels` (Euclidean) of a masked pixel of the same frame.

    Examples
    --------
    >>> m = np.zeros((5, 5), bool); m[2, 2] = True
    >>> int(grow_masks(m, 1).sum())
    5
    """
    masks = np.asarray(masks, bool)
    frames = masks.reshape((-1, *masks.shape[-2:]))
    return np.stack([grow_mask(mask, pixels) for mask in frames]).reshape(masks.shape)


@dataclass(frozen=True)
class WindowWork:
    """What restores a window of frames: a detector, a filler and their temporal reach.

    Parameters
    ----------
    fill : callable
        ``fill(frames, masks, channel_axis=...)`` -> frames of the same shape and dtype,
        with frames (n, H, W[, C]) and masks (n, H, W) bool.
    detect : callable, optional
        ``detect(frames, channel_axis=...)`` -> masks (n, H, W) bool, or (masks, kinds)
        with kinds int8 of the same shape. None: masks are given with the frames.
    fill_radius : int
        The frames either side that filling one frame reads.
    detect_radius : int
        The frames either side that detecting one frame's mask reads.
    grow : float
        Pixels by which given masks are grown before filling (detected masks are grown by
        the detector itself).
    fill_kinds : bool
        The filler takes the detector's kinds, ``fill(frames, masks, channel_axis=...,
        kinds=...)`` with kinds int8 (n, H, W), where the detector reports them (never
        with given masks).

    Examples
    --------
    >>> import clpde
    >>> def spatial(frames, masks, channel_axis=None):
    ...     return np.stack([clpde.inpaint(f, m, channel_axis=channel_axis)
    ...                      for f, m in zip(frames, masks)])
    >>> work = WindowWork(fill=spatial, fill_radius=0)
    """

    fill: Callable
    detect: Callable | None = None
    fill_radius: int = 0
    detect_radius: int = 0
    grow: float = 0
    fill_kinds: bool = False

    def context(self, detecting: bool) -> int:
        """Frames of context either side of a block."""
        return self.fill_radius + (self.detect_radius if detecting else 0)


def _channel_axis(frames: np.ndarray) -> int | None:
    return -1 if frames.ndim == 4 else None


def _expand(masks: np.ndarray, frames: np.ndarray) -> np.ndarray:
    return masks[..., np.newaxis] if frames.ndim == masks.ndim + 1 else masks


def restore_window(
    work: WindowWork, frames: np.ndarray, masks: np.ndarray | None, block: Block
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Restore one block from its window.

    Parameters
    ----------
    work : WindowWork
        The detector and filler.
    frames : ndarray
        The window's frames [block.first, block.last), (n, H, W[, C]).
    masks : ndarray of bool, optional
        Given masks for the same frames; None: detect them.
    block : Block
        Which frames of the window to restore.

    Returns
    -------
    (ndarray, ndarray, ndarray or None)
        The block's restored frames, its masks, and the defect kinds (int8) when the
        detector reports them.

    Raises
    ------
    InputError
        If the window's arrays do not match the block, or the work's results do not match
        the frames.
    """
    n = block.last - block.first
    if len(frames) != n or (masks is not None and len(masks) != n):
        raise InputError(
            f"a window of {n} frames got {len(frames)} frames"
            + ("" if masks is None else f" and {len(masks)} masks")
        )
    axis = _channel_axis(frames)
    kinds = None
    if masks is None:
        if work.detect is None:
            raise InputError("no masks given and no detector to find them")
        found = work.detect(frames, channel_axis=axis)
        masks, kinds = found if isinstance(found, tuple) else (found, None)
    else:
        masks = grow_masks(masks, work.grow)
    masks = np.asarray(masks, bool)
    if masks.shape != frames.shape[:3]:
        raise InputError(f"the masks are {masks.shape}, the frames {frames.shape[:3]}")
    # Fill the block with fill_radius frames either side: their masks were detected with
    # their own context above, which is why the window reaches further than the fill.
    lo = max(block.first, block.start - work.fill_radius) - block.first
    hi = min(block.last, block.stop + work.fill_radius) - block.first
    keep = slice(block.start - block.first, block.stop - block.first)
    inner = slice(keep.start - lo, keep.stop - lo)
    if masks[lo:hi].any():
        # the kinds of the same frames as the masks: a frame's fill reads its own
        extra = {}
        if work.fill_kinds and kinds is not None:
            extra["kinds"] = np.ascontiguousarray(np.asarray(kinds, np.int8)[lo:hi])
        filled = work.fill(
            np.ascontiguousarray(frames[lo:hi]),
            np.ascontiguousarray(masks[lo:hi]),
            channel_axis=axis,
            **extra,
        )
        filled = np.asarray(filled)
        if filled.shape != frames[lo:hi].shape:
            raise InputError(f"the filler returned {filled.shape} for frames {frames[lo:hi].shape}")
        # Pixels outside the masks stay the input's exactly, whatever the filler does there.
        restored = np.where(
            _expand(masks[keep], frames), filled[inner].astype(frames.dtype), frames[keep]
        )
    else:
        restored = frames[keep]
    return (
        np.ascontiguousarray(restored),
        np.ascontiguousarray(masks[keep]),
        None if kinds is None else np.ascontiguousarray(np.asarray(kinds, np.int8)[keep]),
    )


def iter_spans(
    frames: Iterable[np.ndarray],
    spans: Iterable[tuple[int, int]],
    masks: Iterable[np.ndarray] | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray | None]]:
    """The frames (and masks) of consecutive spans [a, b), read once from iterators.

    Parameters
    ----------
    frames : iterable of ndarray
        The film's frames in order.
    spans : iterable of (int, int)
        Spans whose starts and ends never decrease.
    masks : iterable of ndarray, optional
        One mask per frame, read alongside.

    Yields
    ------
    (ndarray, ndarray or None)
        The span's frames stacked (n, H, W[, C]) and its masks (n, H, W).

    Raises
    ------
    InputError
        If the film ends before a span, or the frames change size.
    """
    frames = iter(frames)
    masks = None if masks is None else iter(masks)
    held: deque = deque()  # (frame, mask) of the frames [base, base + len(held))
    base = 0
    size = None
    for a, b in spans:
        while base < a and held:  # frames no span needs again
            held.popleft()
            base += 1
        while base + len(held) < b:
            index = base + len(held)
            frame = next(frames, None)
            if frame is None:
                raise InputError(f"the film ended at frame {index}, before frame {b}")
            mask = None if masks is None else next(masks, None)
            if masks is not None and mask is None:
                raise InputError(f"the masks ended at frame {index}; give one mask per frame")
            size = frame.shape if size is None else size
            if frame.shape != size:
                raise InputError(
                    f"frame {index} is {frame.shape}, the film {size}; all frames need one size"
                )
            if index < a:  # before the span (a gap between spans): read past, never held
                base += 1
                continue
            held.append((frame, mask))
        window = [held[k] for k in range(b - a)]
        yield (
            np.stack([f for f, _ in window]),
            None if masks is None else np.stack([m for _, m in window]),
        )


def restore_stream(
    frames: Iterable[np.ndarray],
    count: int,
    work: WindowWork,
    *,
    masks: Iterable[np.ndarray] | None = None,
    block: int = DEFAULT_BLOCK,
    span: tuple[int, int] | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray | None]]:
    """Restore a film frame by frame in one process, holding one window at a time.

    Parameters
    ----------
    frames : iterable of ndarray
        The film's `count` frames in order, (H, W[, C]) each.
    count : int
        The number of frames.
    work : WindowWork
        The detector and filler.
    masks : iterable of ndarray, optional
        Given masks, one per frame (then nothing is detected).
    block : int
        Frames restored per window (the grid: see the module's text).
    span : (int, int), optional
        Restore only the frames [start, stop): the frames before are read past, and the
        section's frames come out as in a run of the whole film.

    Yields
    ------
    (ndarray, ndarray, ndarray or None)
        Each frame restored, its mask, and its defect kinds (when detected with kinds), in
        frame order.

    Examples
    --------
    >>> work = WindowWork(fill=lambda f, m, channel_axis=None: f)
    >>> film = np.zeros((3, 4, 4), np.uint8)
    >>> [r.shape for r, _, _ in restore_stream(film, 3, work, masks=film > 0, block=2)]
    [(4, 4), (4, 4), (4, 4)]
    """
    context = work.context(masks is None)
    plan = plan_blocks(count, block, context, span)
    spans = [(b.first, b.last) for b in plan]
    with keep_flows(_kept_flows(context)):
        for blk, (window, window_masks) in zip(plan, iter_spans(frames, spans, masks), strict=True):
            restored, found, kinds = restore_window(work, window, window_masks, blk)
            for k in range(len(restored)):
                yield restored[k], found[k], None if kinds is None else kinds[k]


def _kept_flows(context: int) -> int:
    """How many flows the detector's motion keeps for the next window (clpde.film._motion's
    keep_flows): the flows among the 2 * context frames two windows share, about FLOWS_KEPT
    per frame."""
    return FLOWS_KEPT * 2 * context


def run_chunk(
    work: WindowWork, frames: np.ndarray, masks: np.ndarray | None, blocks: list[Block]
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Restore consecutive blocks from one array of frames (a chunk on a Dask worker).

    Parameters
    ----------
    work : WindowWork
        The detector and filler.
    frames : ndarray
        The frames [blocks[0].first, blocks[-1].last).
    masks : ndarray, optional
        Given masks for the same frames.
    blocks : list of Block
        Consecutive blocks of the grid.

    Returns
    -------
    (ndarray, ndarray, ndarray or None)
        The restored frames, masks and kinds of [blocks[0].start, blocks[-1].stop).
    """
    offset = blocks[0].first
    parts = []
    with keep_flows(_kept_flows(work.context(masks is None))):
        for blk in blocks:
            window = slice(blk.first - offset, blk.last - offset)
            parts.append(
                restore_window(
                    work,
                    np.ascontiguousarray(frames[window]),
                    None if masks is None else np.ascontiguousarray(masks[window]),
                    blk,
                )
            )
    kinds = None if parts[0][2] is None else np.concatenate([p[2] for p in parts])
    return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]), kinds)


# ---- the library's own detector and filler ------------------------------------------------
def _call(function: Callable, frames: np.ndarray, *args, channel_axis=None, **options):
    return function(frames, *args, channel_axis=channel_axis, **options)


def _default(function: Callable, name: str) -> int:
    return int(inspect.signature(function).parameters[name].default)


def film_work(
    *, grow: float = 0, detect_options: dict | None = None, fill_options: dict | None = None
) -> WindowWork:
    """clpde's film restoration as window work: clpde.detect_defects and clpde.inpaint_video.

    Parameters
    ----------
    grow : float
        Pixels by which masks are grown (detected ones through the detector's `grow`).
    detect_options : dict, optional
        Keywords for clpde.detect_defects.
    fill_options : dict, optional
        Keywords for clpde.inpaint_video.

    Returns
    -------
    WindowWork
        With the detector's and filler's temporal reach.

    Examples
    --------
    >>> film_work(grow=2).context(detecting=True)
    7
    """
    detect_options = {"return_kinds": True, "grow": grow, **(detect_options or {})}
    # detected masks: a pixel the fill would barely change keeps its value (do no harm)
    fill_options = {"keep": KEEP, **(fill_options or {})}
    # The detector compares a frame with `radius` frames either side, and then reads the
    # line scores of the frames either side of it (a scratch continues over frames), and
    # the next and previous frames (a moving object reappears there): one frame further.
    detect_radius = detect_options.get("radius", _default(detect_defects, "radius")) + 1
    fill_radius = fill_options.get("radius", _default(inpaint_video, "radius"))
    return WindowWork(
        fill=functools.partial(_call, inpaint_video, **fill_options),
        detect=functools.partial(_call, detect_defects, **detect_options),
        fill_radius=int(fill_radius),
        detect_radius=int(detect_radius),
        grow=grow,
        fill_kinds=True,
    )
