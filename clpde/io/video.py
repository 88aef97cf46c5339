"""Video files through PyAV: the one video reader and the one video writer of clpde.

H.264 in 4:2:0 needs even sizes: an odd-sized film is padded by one row or column (edge
pixels repeated) for the encoder, and its size is kept in the file's metadata so that
``read_video`` crops it back; frames are never rescaled.
"""

from __future__ import annotations

import contextlib
import hashlib
import re
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from .images import atomic_output

VIDEO_FORMATS = {".mp4": "mp4", ".mov": "mov", ".mkv": "matroska", ".avi": "avi", ".m4v": "mp4"}
READ_SUFFIXES = set(VIDEO_FORMATS) | {".webm", ".mpg", ".mpeg", ".ogv"}
_SIZE_TAG = "comment"  # container metadata: "clpde size=WxH" when the frames were padded
_SIZE_RE = re.compile(r"clpde size=(\d+)x(\d+)")


def is_video(path) -> bool:
    return Path(path).suffix.lower() in READ_SUFFIXES


def require_av():
    """PyAV, or a clear error naming the fix."""
    try:
        import av
    except ImportError:
        raise InputError(
            'reading and writing video needs PyAV: pip install "clpde[video]"'
        ) from None
    return av


# ---- video files ------------------------------------------------------------------------------
@dataclass
class VideoInfo:
    frames: int  # as the container states it (0 when unknown)
    rate: Fraction
    width: int
    height: int


def video_info(path) -> VideoInfo:
    av = require_av()
    with _open_input(av, path) as container:
        stream = container.streams.video[0]
        width, height = _stored_size(container, stream)
        return VideoInfo(int(stream.frames or 0), _rate(stream), width, height)


@contextlib.contextmanager
def _open_input(av, path):
    path = Path(path)
    if not path.is_file():
        raise InputError(f"input video {path} does not exist")
    try:
        container = av.open(str(path))
    except Exception as exc:  # noqa: BLE001  (PyAV raises many types: all mean unreadable)
        raise InputError(f"cannot read {path} as a video: {exc}") from None
    try:
        if not container.streams.video:
            raise InputError(f"{path} holds no video stream")
        yield container
    finally:
        container.close()


def _rate(stream) -> Fraction:
    rate = stream.average_rate or stream.base_rate or stream.guessed_rate
    return Fraction(rate) if rate else Fraction(25)


def _stored_size(container, stream) -> tuple[int, int]:
    """The frames' size before padding (from our metadata), else the stream's."""
    match = _SIZE_RE.search(container.metadata.get(_SIZE_TAG, ""))
    width, height = stream.codec_context.width, stream.codec_context.height
    if match:
        w, h = int(match.group(1)), int(match.group(2))
        if w <= width and h <= height:
            return w, h
    return width, height


def iter_video(path):
    """The frames of a video as (rows, columns, 3) uint8 RGB arrays, in display order."""
    av = require_av()
    with _open_input(av, path) as container:
        stream = container.streams.video[0]
        width, height = _stored_size(container, stream)
        try:
            for frame in container.decode(stream):
                # An array of its own: PyAV's shares the frame's buffer, and a batch of
                # frames waits (and is sent) while the next ones are decoded.
                yield np.array(frame.to_ndarray(format="rgb24")[:height, :width])
        except av.FFmpegError as exc:
            raise InputError(f"cannot decode {path}: {exc}") from None


def read_video(path) -> tuple[np.ndarray, Fraction]:
    """(frames (T, rows, columns, 3) uint8, frame rate) of a video file."""
    frames = list(iter_video(path))
    if not frames:
        raise InputError(f"{path} holds no frames")
    return np.stack(frames), video_info(path).rate


class VideoWriter:
    """Frames into a video file with PyAV (H.264, 4:2:0), written atomically: the file
    appears under its name only when close() succeeds; abort() (or an error in a with
    block) leaves nothing.

    Reproducible: the same frames give the same bytes, run after run and whatever ran in
    the process before. x264's macroblock-tree rate control reads memory that it never
    initialised (glibc's MALLOC_PERTURB_=1 alone changes a film from 105 to 124 kB), so
    with it a film restored over workers and one restored serially differed in bytes with
    the same frames; it is off (mbtree=0: 5% larger, 0.3 dB lower PSNR on the carphone clip
    at crf 17). threads: the encoder's (0: FFmpeg's choice); x264's output depends on their
    number, so the default 1 gives the same bytes on any machine.
    """

    def __init__(self, path, rate, *, crf: int = 17, codec: str = "libx264", threads: int = 1):
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in VIDEO_FORMATS:
            raise InputError(f"{path}: write a video as one of {', '.join(sorted(VIDEO_FORMATS))}")
        if not path.parent.is_dir():
            raise InputError(f"output folder {path.parent} does not exist; create it first")
        if isinstance(threads, bool) or not isinstance(threads, int) or threads < 0:
            raise InputError(
                f"threads must be a whole number >= 0 (0: FFmpeg's choice), not {threads!r}"
            )
        self.path, self.rate, self.crf, self.codec = path, Fraction(rate), crf, codec
        self.threads = threads
        self._atomic = atomic_output(path)
        self._tmp = self._atomic.__enter__()
        self._container = require_av().open(str(self._tmp), mode="w", format=VIDEO_FORMATS[suffix])
        self._stream = None
        self.count = 0
        # The frames as given, before the (lossy) encoder: what a film restored over
        # workers and one restored serially must agree on, bit for bit.
        self._digest = hashlib.sha256()

    def _start(self, height: int, width: int) -> None:
        self.size = (height, width)
        stream = self._container.add_stream(self.codec, rate=self.rate)
        stream.width, stream.height = width + width % 2, height + height % 2
        stream.pix_fmt = "yuv420p"
        options = {"crf": str(self.crf)}
        if self.codec == "libx264":  # its mbtree reads uninitialised memory (see above)
            options["x264-params"] = "mbtree=0"
        stream.options = options
        stream.thread_count = self.threads
        if (stream.width, stream.height) != (width, height):
            self._container.metadata[_SIZE_TAG] = f"clpde size={width}x{height}"
        self._stream = stream

    def write(self, frame: np.ndarray) -> None:
        av = require_av()
        frame = np.asarray(frame)
        if frame.ndim == 2:
            frame = np.repeat(frame[..., np.newaxis], 3, axis=-1)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[-1] not in (3, 4):
            raise InputError(
                f"video frames must be 8-bit grey or RGB, not {frame.dtype} of shape {frame.shape}"
            )
        frame = np.ascontiguousarray(frame[..., :3])
        if self._stream is None:
            self._start(*frame.shape[:2])
        if frame.shape[:2] != self.size:
            raise InputError(
                f"frame {self.count} is {frame.shape[1]}x{frame.shape[0]}, the "
                f"film {self.size[1]}x{self.size[0]}; all frames need one size"
            )
        self._digest.update(frame.data)
        pad = (
            (0, self._stream.height - frame.shape[0]),
            (0, self._stream.width - frame.shape[1]),
            (0, 0),
        )
        if any(p[1] for p in pad):
            frame = np.pad(frame, pad, mode="edge")
        picture = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="rgb24")
        picture.pts = self.count
        for packet in self._stream.encode(picture):
            self._container.mux(packet)
        self.count += 1

    @property
    def frames_sha256(self) -> str:
        """SHA-256 of the RGB frames written so far (rows, columns, 3 uint8 each, in order)."""
        return self._digest.hexdigest()

    def close(self) -> Path:
        if self._stream is None:
            self.abort()
            raise InputError(f"no frames to write to {self.path}")
        for packet in self._stream.encode():
            self._container.mux(packet)
        self._container.close()
        self._atomic.__exit__(None, None, None)
        return self.path

    def abort(self) -> None:
        with contextlib.suppress(Exception):
            self._container.close()
        with contextlib.suppress(BaseException):
            self._atomic.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.close()
        else:
            self.abort()


def write_video(path, frames, rate, *, threads: int = 1) -> Path:
    """Write (T, rows, columns[, 3]) uint8 frames as a video at `rate` frames per second
    (`threads`: the encoder's, see VideoWriter)."""
    with VideoWriter(path, rate, threads=threads) as writer:
        for frame in frames:
            writer.write(frame)
    return Path(path)
