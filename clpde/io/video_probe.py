"""What clpde knows of a video file before decoding a frame: the containers and codecs it
reads and writes, a video's description (`video_info`: frame count, rate, size, depth,
colour, metadata), and whether an output can be written (`check_video_output`).

The frames themselves are read and written by clpde.io.video. Interlaced input (frames
made of two fields) is refused here with one line: restoring it frame by frame would mix
two instants.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from .images import PathLike

FORMATS = {".mp4": "mp4", ".m4v": "mp4", ".mov": "mov", ".mkv": "matroska", ".avi": "avi"}
READ_SUFFIXES = set(FORMATS) | {".webm", ".mpg", ".mpeg", ".ogv", ".ts", ".mxf"}
CODECS = {"h264": "libx264", "h265": "libx265", "ffv1": "ffv1"}
LOSSLESS = ("ffv1",)
# The writer pads odd sizes for 4:2:0 and keeps the true size in this tag.
SIZE_TAG = "comment"
SIZE_PATTERN = re.compile(r"clpde size=(\d+)x(\d+)")


def require_av():
    """PyAV, or a clear error naming the fix.

    Returns
    -------
    module
        The ``av`` module.

    Raises
    ------
    InputError
        If PyAV is not installed.

    Examples
    --------
    >>> require_av().__name__
    'av'
    """
    try:
        import av
    except ImportError:
        raise InputError('video needs PyAV: pip install "clpde[video]"') from None
    return av


def is_video(path: PathLike) -> bool:
    """Whether `path` names a video file (by its extension).

    Parameters
    ----------
    path : str or PathLike
        The file name.

    Returns
    -------
    bool
        True for the extensions the reader takes (.mp4, .mkv, .mov, .avi, .webm, ...).

    Examples
    --------
    >>> is_video("reel.MKV"), is_video("scan.png")
    (True, False)
    """
    return Path(path).suffix.lower() in READ_SUFFIXES


@dataclass
class VideoInfo:
    """What a video stream is, and the streams that travel with it.

    Attributes
    ----------
    path : Path
        The video file.
    frames : int
        The number of video frames (counted from the packets).
    rate : Fraction
        Frames per second.
    time_base : Fraction
        The unit of the video stream's timestamps.
    width, height : int
        The frames' size (before any padding the writer added for 4:2:0).
    pix_fmt : str
        The stored pixel format (e.g. ``yuv420p10le``).
    depth : int
        Bits per component of the stored pixels.
    colour : dict
        The colour matrix, range, primaries and transfer (FFmpeg's codes).
    metadata : dict
        The container's tags.
    video_metadata : dict
        The video stream's tags.
    """

    path: Path
    frames: int
    rate: Fraction
    time_base: Fraction
    width: int
    height: int
    pix_fmt: str
    depth: int
    colour: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    video_metadata: dict = field(default_factory=dict)

    @property
    def dtype(self) -> np.dtype:
        """The frames' dtype: uint8 for 8-bit videos, uint16 for deeper ones."""
        return np.dtype(np.uint8 if self.depth <= 8 else np.uint16)


@contextlib.contextmanager
def open_video(path: PathLike):
    """The video file opened by PyAV (closed on leaving), or one line saying why not."""
    av = require_av()
    path = Path(path)
    if not path.is_file():
        raise InputError(f"input film {path} does not exist")
    try:
        container = av.open(str(path))
    except Exception as exc:  # noqa: BLE001  (PyAV raises many types: all mean unreadable)
        detail = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise InputError(f"cannot read {path} as a film: {detail}") from None
    try:
        if not container.streams.video:
            raise InputError(f"{path} holds no video stream; give a film with pictures")
        yield container
    finally:
        container.close()


def stored_size(container, stream) -> tuple[int, int]:
    """(width, height) of the frames: before the writer's 4:2:0 padding, else the stream's."""
    width, height = stream.codec_context.width, stream.codec_context.height
    match = SIZE_PATTERN.search(container.metadata.get(SIZE_TAG, ""))
    if match and int(match.group(1)) <= width and int(match.group(2)) <= height:
        return int(match.group(1)), int(match.group(2))
    return width, height


def video_info(path: PathLike) -> VideoInfo:
    """Read a video's description, and refuse what clpde cannot read.

    Parameters
    ----------
    path : str or PathLike
        The video file.

    Returns
    -------
    VideoInfo
        Its frame count, rate, size, depth, colour and metadata.

    Raises
    ------
    InputError
        If the file does not exist, cannot be read, holds no video stream or no frames, or
        is interlaced.

    Examples
    --------
    >>> video_info("film.mp4").frames  # doctest: +SKIP
    3000
    """
    av = require_av()
    with open_video(path) as container:
        stream = container.streams.video[0]
        cc = stream.codec_context
        width, height = stored_size(container, stream)
        # The packets, not the header: MKV states no count, and MP4's may be an edit list's.
        count = sum(1 for p in container.demux(stream) if p.size)
        if count == 0:
            raise InputError(f"{path} holds no video frames")
        container.seek(0)
        first = next(container.decode(stream), None)
    if first is None:
        raise InputError(f"{path}: the first video frame cannot be decoded")
    if first.interlaced_frame:
        raise InputError(
            f"{path} is interlaced (each frame holds two fields); deinterlace it "
            "first, e.g. ffmpeg -i IN -vf bwdif=mode=send_field OUT"
        )
    rate = stream.average_rate or stream.base_rate or stream.guessed_rate or 25
    fmt = av.VideoFormat(cc.pix_fmt or first.format.name)
    colour = {
        "range": int(first.color_range),
        "space": int(first.colorspace),
        "primaries": int(first.color_primaries),
        "trc": int(first.color_trc),
    }
    return VideoInfo(
        Path(path),
        count,
        Fraction(rate),
        Fraction(stream.time_base),
        width,
        height,
        fmt.name,
        max(c.bits for c in fmt.components),
        colour,
        dict(container.metadata),
        dict(stream.metadata),
    )


def check_video_output(path: PathLike, codec: str | None = None) -> tuple[str, str]:
    """Check, before any work, that a video can be written at `path` with `codec`.

    Parameters
    ----------
    path : str or PathLike
        The video to write.
    codec : {'h264', 'h265', 'ffv1'}, optional
        The video codec (default h264).

    Returns
    -------
    (str, str)
        The container format and the codec's name.

    Raises
    ------
    InputError
        For an unknown container or codec, FFV1 outside Matroska, or a folder that does not
        exist or is not writable.

    Examples
    --------
    >>> check_video_output("out.mkv", "ffv1")
    ('matroska', 'ffv1')
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise InputError(f"{path}: write a film as one of {', '.join(sorted(FORMATS))}")
    codec = codec or "h264"
    if codec not in CODECS:
        raise InputError(f"--codec {codec}: choose one of {', '.join(CODECS)}")
    if codec == "ffv1" and FORMATS[suffix] != "matroska":
        raise InputError(f"{path}: lossless FFV1 goes in Matroska; name the output .mkv")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(
            f"output folder {folder} does not exist (or is not a folder); create it first"
        )
    if path.is_dir():
        raise InputError(f"output {path} is a folder; give a film file name")
    try:  # writable at all? (a read-only folder or file system)
        fd, probe = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".part")
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror} in folder {folder}") from None
    os.close(fd)
    os.unlink(probe)
    return FORMATS[suffix], codec
