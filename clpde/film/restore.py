"""Restore a film or a folder of frames into a film or a folder: the path behind both
``clpde restore`` and ``clpde inpaint VIDEO``.

The frames stream through clpde.film.stream's sliding window in this process, or through
clpde.film.chunks on Dask's workers when a cluster is asked for; either way only a window
(or a few chunks) of frames is in memory. Everything is checked before the first frame is
read (the output's folder and codec, the masks' count and size), and every output (the film
or folder, the masks folder, the overlay) appears only when complete: an error or Ctrl-C
leaves none of them.
"""

from __future__ import annotations

import contextlib
import hashlib
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from .._progress import progress_bar
from ..errors import InputError
from ..io.frames import FrameSource, image_files
from ..io.images import PathLike, output_folder, read_mask, write_image
from ..io.video import VideoWriter
from ..io.video_probe import FORMATS, check_video_output
from .chunks import restore_chunked
from .stream import DEFAULT_BLOCK, WindowWork, film_work, restore_stream

# The overlay's colours per defect kind: given or unclassified masks, blotches, scratches.
OVERLAY_COLOURS = {0: (255, 40, 40), 1: (255, 40, 40), 2: (255, 220, 0)}


@dataclass
class FilmResult:
    """What a restoration did.

    Attributes
    ----------
    output : Path
        The restored film or folder.
    frames : int
        Frames restored.
    rate : Fraction
        Frames per second of the output.
    seconds : float
        Wall time of the whole run.
    masked_pixels : int
        Pixels filled, over all frames.
    workers : int
        Dask workers (0: this process).
    frames_sha256 : str
        SHA-256 of the restored frames in order (before any lossy encoder): what a run on
        workers and one in a process agree on, bit for bit.
    filled_per_frame : list of int
        Pixels filled in each frame written, in frame order (the masks' counts).
    first : int
        The film's frame number of the first frame written (a section's start; else 0).
    """

    output: Path
    frames: int
    rate: Fraction
    seconds: float
    masked_pixels: int
    workers: int
    frames_sha256: str
    filled_per_frame: list = field(default_factory=list)
    first: int = 0

    def most_filled(self, count: int = 5) -> list[tuple[int, int]]:
        """The `count` frames with most pixels filled, as (frame number in the film, pixels),
        most first."""
        per = self.filled_per_frame
        order = sorted(range(len(per)), key=lambda t: -per[t])
        return [(self.first + t, per[t]) for t in order[:count] if per[t]]


def _frame_name(source: FrameSource, t: int, dtype: np.dtype, channels: int) -> str:
    """Frame t's file name in an output folder: the input's, else frame_00000.png."""
    if source.files is not None:
        return source.files[t].name
    suffix = ".tif" if dtype != np.uint8 and channels > 1 else ".png"
    return f"frame_{t:05d}{suffix}"


def _mask_source(mask: PathLike, source: FrameSource) -> Iterator[np.ndarray]:
    """One mask per frame: the same file for every frame, or the t-th of a folder. The
    count and the first mask's size are checked at once, before any frame is read."""
    mask = Path(mask)
    shape = source.shape[:2]
    if mask.is_dir():
        files = image_files(mask)
        if len(files) != source.count:
            raise InputError(
                f"the mask folder {mask} holds {len(files)} masks for "
                f"{source.count} frames; give one mask per frame (or one mask file)"
            )
        read_mask(files[0], shape, what="the frames")

        def each():
            for path in files:
                yield read_mask(path, shape, what="the frames")

        return each()
    if not mask.is_file():
        raise InputError(f"mask {mask} does not exist")
    single = read_mask(mask, shape, what="the frames")

    def same():
        for _ in range(source.count):
            yield single

    return same()


def _overlay_frame(frame: np.ndarray, mask: np.ndarray, kinds: np.ndarray | None) -> np.ndarray:
    """The frame (as 8-bit RGB) with its masked pixels tinted by defect kind."""
    if frame.dtype == np.uint16:
        frame = (frame >> 8).astype(np.uint8)
    elif frame.dtype != np.uint8:
        frame = np.clip(np.nan_to_num(frame.astype(np.float64)) * 255, 0, 255).astype(np.uint8)
    if frame.ndim == 2:
        frame = np.repeat(frame[..., np.newaxis], 3, axis=-1)
    out = frame[..., :3].astype(np.float32)
    kinds = np.zeros(mask.shape, np.int8) if kinds is None else kinds
    for kind, colour in OVERLAY_COLOURS.items():
        where = mask & (kinds == kind)
        out[where] = 0.35 * out[where] + 0.65 * np.asarray(colour, np.float32)
    return out.round().astype(np.uint8)


def _check_outputs(
    source: FrameSource,
    output: Path,
    masks_out: Path | None,
    overlay: Path | None,
    codec: str | None,
    grow: float,
) -> bool:
    """Check every output before any frame is read; True when the output is a film."""
    to_film = output.suffix.lower() in FORMATS
    if not to_film and output.suffix:
        raise InputError(
            f"output {output}: give a film ({', '.join(sorted(FORMATS))}) or a "
            "folder for the restored frames"
        )
    paths = [output, *[p for p in (masks_out, overlay) if p is not None]]
    for path in paths:
        if path.resolve() == source.path.resolve():
            raise InputError(f"output {path} is the input; clpde never overwrites its inputs")
    if len({p.resolve() for p in paths}) != len(paths):
        raise InputError("the output, --masks-out and --overlay must be different paths")
    if to_film:
        check_video_output(output, codec)
    elif codec is not None:
        raise InputError("--codec applies to a film output, not a folder of frames")
    if overlay is not None:
        check_video_output(overlay)
    if grow < 0:
        raise InputError(f"--grow must be >= 0 pixels, not {grow}")
    return to_film


class _Outputs:
    """The restored film or folder, the masks folder and the overlay, written frame by frame
    inside one ExitStack (so that an error or Ctrl-C leaves none of them)."""

    def __init__(
        self,
        stack: contextlib.ExitStack,
        source: FrameSource,
        output: Path,
        to_film: bool,
        *,
        codec: str | None,
        masks_out: Path | None,
        overlay: Path | None,
        overwrite: bool,
        option: str,
        first: int = 0,
    ) -> None:
        self.source = source
        self.first = first
        like = source.reader.info if source.reader is not None else None
        self.film = self.folder = self.masks = self.overlay = self.originals = None
        if to_film:
            # A section starts at time 0, without the film's sound (it would be out of step).
            self.film = stack.enter_context(
                VideoWriter(output, source.rate, like=like, codec=codec, copy_streams=not first)
            )
        else:
            self.folder = stack.enter_context(output_folder(output, overwrite, option=option))
        if masks_out is not None:
            self.masks = stack.enter_context(output_folder(masks_out, overwrite, option=option))
        if overlay is not None:
            self.overlay = stack.enter_context(
                VideoWriter(overlay, source.rate, like=like, copy_streams=False)
            )
            # The overlay draws over the damaged frames: a second reader, in step.
            self.originals = iter(FrameSource(source.path))
            for _ in range(first):
                next(self.originals)
        self.digits = max(5, len(str(source.count - 1)))
        self.digest = hashlib.sha256()
        self.masked = self.written = 0
        self.per_frame: list[int] = []
        self.start_pts = 0

    def write(self, frame: np.ndarray, found: np.ndarray, kinds: np.ndarray | None) -> None:
        t = self.first + self.written  # the frame's number in the film
        self.digest.update(np.ascontiguousarray(frame).data)
        self.per_frame.append(int(found.sum()))
        self.masked += self.per_frame[-1]
        timestamps = self.source.reader.timestamps if self.source.reader is not None else None
        if timestamps and self.written == 0 and self.first:
            # the frames before a section were read past: drop their timestamps, and start
            # the section at time 0
            del timestamps[: self.first]
            self.start_pts = timestamps[0]
        pts = timestamps.pop(0) - self.start_pts if timestamps else None
        if self.film is not None:
            self.film.write(frame, pts=pts)
        else:
            channels = frame.shape[-1] if frame.ndim == 3 else 1
            write_image(self.folder / _frame_name(self.source, t, frame.dtype, channels), frame)
        if self.masks is not None:
            name = f"mask_{t:0{self.digits}d}.png"
            write_image(self.masks / name, found.astype(np.uint8) * 255)
        if self.overlay is not None:
            self.overlay.write(_overlay_frame(next(self.originals), found, kinds), pts=pts)
        self.written += 1


def restore_film(
    source: PathLike,
    output: PathLike,
    *,
    mask: PathLike | None = None,
    masks_out: PathLike | None = None,
    grow: float = 0,
    overlay: PathLike | None = None,
    codec: str | None = None,
    work: WindowWork | None = None,
    detect_options: dict | None = None,
    fill_options: dict | None = None,
    block: int = DEFAULT_BLOCK,
    cluster=None,
    client=None,
    chunk_frames: int | None = None,
    overwrite: bool = False,
    overwrite_option: str = "overwrite=True",
    progress: bool | None = None,
    frames: tuple[int, int] | None = None,
) -> FilmResult:
    """Find the damage in a film and fill it from the neighbouring frames, film in, film out.

    Parameters
    ----------
    source : str or PathLike
        A film (.mp4, .mkv, .mov, .avi, ...) or a folder of frames (PNG, TIFF, JPEG).
    output : str or PathLike
        A film (.mp4, .mkv, .mov, .avi), or a folder for the frames.
    mask : str or PathLike, optional
        Masks to fill instead of detecting: one image for every frame, or a folder of one
        per frame (in name order).
    masks_out : str or PathLike, optional
        A folder for the masks used, one PNG per frame (mask_00000.png, ...).
    grow : float
        Pixels by which the masks are grown (a lossy codec spreads damage past its edge).
    overlay : str or PathLike, optional
        A film of the frames with the masks drawn over them (red: blotches and given masks,
        yellow: line scratches).
    codec : {'h264', 'h265', 'ffv1'}, optional
        The output film's codec (default h264; ffv1 is lossless, in .mkv).
    work : WindowWork, optional
        The detector and filler (default: clpde.detect_defects and clpde.inpaint_video).
    detect_options, fill_options : dict, optional
        Keywords for the default detector and filler.
    block : int
        Frames restored per window.
    cluster : context manager, optional
        Run on Dask, on the client of the (client, info) pair this yields, entered once the
        inputs and outputs are checked and left at the end: what
        ``clpde.scale.cluster.connect(workers, scheduler)`` returns, a local cluster of
        `workers` or a running one at `scheduler` (the command line's --workers and
        --scheduler).
    client : distributed.Client, optional
        Run on Dask, on this open client (left open). Neither: this process.
    chunk_frames : int, optional
        Frames per Dask task (rounded up to whole blocks).
    overwrite : bool
        Replace an output folder (of clpde's kinds of files).
    overwrite_option : str
        How the caller spells `overwrite`, for messages.
    progress : bool, optional
        A progress bar in frames per second (None: on a terminal).
    frames : (int, int), optional
        Restore only the frames first..last (from 0, both included) to try a section: the
        frames outside it are read as context, so the section comes out as in a run of the
        whole film. A section's film starts at time 0 and has no sound.

    Returns
    -------
    FilmResult
        The output, frame count, rate, time and digest of the restored frames.

    Raises
    ------
    InputError
        For a missing or unreadable input, a film without video or an interlaced one,
        masks of the wrong count or size, an output that cannot be written, an output
        that is the input, or `frames` outside the film; nothing is written.

    Examples
    --------
    >>> restore_film("dusty.mp4", "clean.mkv", codec="ffv1", grow=2)  # doctest: +SKIP
    """
    start = time.perf_counter()
    src = FrameSource(source)
    output = Path(output)
    masks_out = None if masks_out is None else Path(masks_out)
    overlay = None if overlay is None else Path(overlay)
    to_film = _check_outputs(src, output, masks_out, overlay, codec, grow)
    span = _section(frames, src.count)
    given = None if mask is None else _mask_source(mask, src)
    if work is None:
        work = film_work(grow=grow, detect_options=detect_options, fill_options=fill_options)
    elif grow and not work.grow:
        work = WindowWork(work.fill, work.detect, work.fill_radius, work.detect_radius, grow)
    if given is None and work.detect is None:
        raise InputError("give the masks (--mask): this restoration has no detector")
    if cluster is not None and client is not None:
        raise InputError("give a cluster to open or an open client, not both")
    with contextlib.ExitStack() as stack:
        outputs = _Outputs(
            stack,
            src,
            output,
            to_film,
            codec=codec,
            masks_out=masks_out,
            overlay=overlay,
            overwrite=overwrite,
            option=overwrite_option,
            first=span[0],
        )
        bar = progress_bar(progress, span[1] - span[0], "clpde restore", unit="frame")
        stack.callback(bar.close)
        if cluster is not None:
            client, _ = stack.enter_context(cluster)
        if client is None:
            restored = restore_stream(src, src.count, work, masks=given, block=block, span=span)
        else:
            restored = restore_chunked(
                client,
                src,
                src.count,
                work,
                masks=given,
                block=block,
                chunk_frames=chunk_frames,
                span=span,
            )
        stack.callback(restored.close)  # Ctrl-C: cancel the workers' chunks too
        for frame, found, kinds in restored:
            outputs.write(frame, found, kinds)
            bar.update(1)
        workers_used = 0 if client is None else len(client.scheduler_info()["workers"])
    if outputs.written != span[1] - span[0]:
        raise InputError(f"restored {outputs.written} of {span[1] - span[0]} frames")
    return FilmResult(
        output,
        outputs.written,
        src.rate,
        time.perf_counter() - start,
        outputs.masked,
        workers_used,
        outputs.digest.hexdigest(),
        outputs.per_frame,
        span[0],
    )


def _section(frames: tuple[int, int] | None, count: int) -> tuple[int, int]:
    """The frames [start, stop) to restore from `frames` = (first, last), both included."""
    if frames is None:
        return 0, count
    first, last = (int(v) for v in frames)
    if not 0 <= first <= last < count:
        raise InputError(
            f"frames {first}:{last} are not within the film's 0:{count - 1}; give "
            f"--frames FIRST:LAST with 0 <= FIRST <= LAST <= {count - 1}"
        )
    return first, last + 1


def write_preview(
    source: PathLike, output: PathLike, folder: PathLike, frames: list[int], first: int = 0
) -> list[Path]:
    """Before | after side by side for the given frames: one PNG per frame in `folder`
    (preview_00012.png, ...), the input on the left and the restored frame on the right,
    each written complete (an error leaves no partial image).

    Parameters
    ----------
    source, output : str or PathLike
        The film (or folder) restored and the restoration's output.
    folder : str or PathLike
        Where the pictures go (created if missing).
    frames : list of int
        Frame numbers in the film (from 0).
    first : int
        The film's frame number of the output's first frame (a section's start).

    Returns
    -------
    list of Path
        The pictures written, in frame order.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    wanted = sorted(set(frames))
    written = []
    before = iter(FrameSource(source))
    after = iter(FrameSource(output))
    for _ in range(first):
        next(before)
    for t in range(first, max(wanted, default=-1) + 1):
        a, b = next(before), next(after)
        if t in wanted:
            side = np.concatenate([a, b], axis=1)
            path = folder / f"preview_{t:05d}.png"
            write_image(path, side)
            written.append(path)
    return written
