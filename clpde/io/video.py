"""Video files through PyAV: clpde's one video reader and one video writer.

A video is read as RGB frames: 8-bit inputs as (rows, columns, 3) uint8, deeper ones (10-bit
and up) as uint16 over the full 16-bit range. Decoding uses the video's own colour matrix
and range, so the frames are what a player shows.

A video is written with the frames' timestamps, the frame rate, and, when it restores an
input (``like=``), that input's colour matrix, range, primaries and transfer, its metadata,
and its audio and subtitle streams (clpde.io.side_streams). Codecs:

- ``h264`` (default) and ``h265``: 4:2:0, 10-bit where the input has more than 8 bits;
  4:2:0 needs even sizes, so an odd-sized video is padded by one row or column (edge pixels
  repeated) and its size kept in the file's metadata, from which the reader crops it back;
- ``ffv1``: lossless, in Matroska, storing the RGB planes (8- or 16-bit), so that the
  written video decodes to exactly the RGB frames that were given to it.

What a video holds (its description, the formats and codecs) is clpde.io.video_probe's.
Writes are atomic: the file appears only when complete.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Iterator
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from .images import PathLike, atomic_output
from .side_streams import SideStreams
from .video_probe import (
    CODECS,
    SIZE_PATTERN,
    SIZE_TAG,
    VideoInfo,
    check_video_output,
    open_video,
    require_av,
    video_info,
)

# Container metadata the muxer writes itself: copying it would record the input's muxer.
_OWN_TAGS = {"major_brand", "minor_version", "compatible_brands", "encoder", "creation_time"}
_STREAM_TAGS = ("language", "title", "handler_name")


# ---- reading ------------------------------------------------------------------------------
def _to_rgb(frame, info: VideoInfo) -> np.ndarray:
    target = "rgb24" if info.depth <= 8 else "rgb48le"
    if frame.format.name in ("rgb24", "rgb48le") and frame.format.name == target:
        rgb = frame
    else:
        rgb = frame.reformat(
            format=target, src_color_range=frame.color_range or None, dst_color_range="JPEG"
        )
    # A copy of its own: PyAV's array shares the frame's buffer, and frames wait (or travel
    # to a worker) while the next ones are decoded.
    return np.array(rgb.to_ndarray()[: info.height, : info.width])


class VideoReader:
    """A video's frames, decoded one at a time in display order, with their timestamps.

    Parameters
    ----------
    path : str or PathLike
        The video file.

    Attributes
    ----------
    info : VideoInfo
        The video's description.
    timestamps : list of int
        The presentation timestamps of the frames read so far that the writer has not yet
        taken (in ``info.time_base``); a restoration pops them in order.

    Raises
    ------
    InputError
        As :func:`video_info`; and a frame that cannot be decoded or is interlaced.

    Examples
    --------
    >>> for frame in VideoReader("film.mp4"):  # doctest: +SKIP
    ...     print(frame.shape, frame.dtype)
    """

    def __init__(self, path: PathLike) -> None:
        self.info = video_info(path)
        self.timestamps: list[int] = []

    def __len__(self) -> int:
        return self.info.frames

    def __iter__(self) -> Iterator[np.ndarray]:
        av = require_av()
        with open_video(self.info.path) as container:
            stream = container.streams.video[0]
            stream.thread_type = "AUTO"
            last = None
            try:
                for t, frame in enumerate(container.decode(stream)):
                    if frame.interlaced_frame:
                        raise InputError(
                            f"{self.info.path}: frame {t} is interlaced; deinterlace the film first"
                        )
                    pts = frame.pts if frame.pts is not None else (last + 1 if last else t)
                    last = pts
                    self.timestamps.append(pts)
                    yield _to_rgb(frame, self.info)
            except av.FFmpegError as exc:
                raise InputError(f"cannot decode {self.info.path}: {exc}") from None


def iter_video(path: PathLike) -> Iterator[np.ndarray]:
    """The frames of a video, one at a time, as :class:`VideoReader` gives them.

    Parameters
    ----------
    path : str or PathLike
        The video file.

    Yields
    ------
    ndarray
        (rows, columns, 3) RGB frames, uint8 (uint16 for deeper videos), in display order.

    Examples
    --------
    >>> first = next(iter_video("film.mp4"))  # doctest: +SKIP
    """
    yield from VideoReader(path)


def read_video(path: PathLike) -> tuple[np.ndarray, Fraction]:
    """All the frames of a video, and its frame rate.

    Parameters
    ----------
    path : str or PathLike
        The video file.

    Returns
    -------
    (ndarray, Fraction)
        The frames (T, rows, columns, 3), uint8 (uint16 for deeper videos), and the rate.

    Raises
    ------
    InputError
        As :class:`VideoReader`.

    Examples
    --------
    >>> frames, rate = read_video("film.mp4")  # doctest: +SKIP
    """
    reader = VideoReader(path)
    return np.stack(list(reader)), reader.info.rate


# ---- writing ------------------------------------------------------------------------------
def _pixel_format(codec: str, depth: int, dtype: np.dtype) -> str:
    if codec == "ffv1":
        return "bgr0" if dtype == np.uint8 else "gbrp16le"
    return "yuv420p" if depth <= 8 else "yuv420p10le"


def _encoder_options(codec: str, crf: int) -> dict:
    if codec == "h264":
        # x264's macroblock-tree reads memory it never initialised: the same frames would
        # give other bytes run after run, and a film restored over workers would differ in
        # bytes from one restored in a process (one thread, for the same reason).
        return {"crf": str(crf), "x264-params": "mbtree=0"}
    if codec == "h265":
        return {"crf": str(crf), "x265-params": "log-level=error"}
    return {"level": "3", "slicecrc": "1", "g": "1"}


def _as_rgb(frame: np.ndarray) -> np.ndarray:
    frame = np.asarray(frame)
    if frame.ndim == 2:
        frame = np.repeat(frame[..., np.newaxis], 3, axis=-1)
    if frame.dtype not in (np.uint8, np.uint16) or frame.ndim != 3 or frame.shape[-1] not in (3, 4):
        raise InputError(
            f"film frames must be 8- or 16-bit grey or RGB, not {frame.dtype} "
            f"of shape {frame.shape}"
        )
    return frame[..., :3]


class VideoWriter:
    """Frames into a video file; restored frames keep the input's timing, colour, sound and
    text.

    Reproducible: the same frames give the same bytes, run after run and whatever ran in
    the process before.

    Parameters
    ----------
    path : str or PathLike
        The video to write (.mp4, .mov, .mkv, .avi); it appears only when :meth:`close`
        succeeds.
    rate : Fraction, optional
        Frames per second (default: `like`'s, else 25).
    like : VideoInfo, optional
        The input video: its timestamps' unit, rate, colour description and metadata are
        kept, and its audio and subtitle streams copied. None: a new video at `rate`.
    codec : {'h264', 'h265', 'ffv1'}, optional
        The video codec (default h264; ffv1 is lossless, in Matroska only).
    crf : int
        The quality of h264 and h265 (lower is better).
    copy_streams : bool
        Copy `like`'s audio and subtitle streams (default True).

    Raises
    ------
    InputError
        See :func:`check_video_output`; and an audio stream that the container cannot hold.

    Examples
    --------
    >>> reader = VideoReader("in.mp4")  # doctest: +SKIP
    >>> with VideoWriter("out.mkv", like=reader.info, codec="ffv1") as writer:  # doctest: +SKIP
    ...     for frame in reader:
    ...         writer.write(frame, pts=reader.timestamps.pop(0))
    """

    def __init__(
        self,
        path: PathLike,
        rate: Fraction | None = None,
        *,
        like: VideoInfo | None = None,
        codec: str | None = None,
        crf: int = 17,
        copy_streams: bool = True,
    ) -> None:
        av = require_av()
        self.path = Path(path)
        self.format, self.codec = check_video_output(self.path, codec)
        self.like, self.crf, self.count = like, crf, 0
        self.rate = Fraction(rate) if rate else (like.rate if like else Fraction(25))
        self._atomic = atomic_output(self.path)
        self._tmp = self._atomic.__enter__()
        self._side: SideStreams | None = None
        try:
            self._out = av.open(str(self._tmp), mode="w", format=self.format)
            self._video = None
            if like is not None:
                for key, value in like.metadata.items():
                    if key not in _OWN_TAGS and not (
                        key == SIZE_TAG and SIZE_PATTERN.search(value)
                    ):
                        self._out.metadata[key] = value
                if copy_streams:
                    self._side = SideStreams.copy(like.path, self._out, self.path, self.format)
        except BaseException:
            self.abort()
            raise

    def _start(self, frame: np.ndarray) -> None:
        height, width = frame.shape[:2]
        depth = self.like.depth if self.like else (8 if frame.dtype == np.uint8 else 16)
        pix_fmt = _pixel_format(self.codec, depth, frame.dtype)
        stream = self._out.add_stream(CODECS[self.codec], rate=self.rate)
        cc = stream.codec_context
        self.size = (height, width)
        pad = pix_fmt.startswith("yuv420")  # 4:2:0 needs even sizes: pad, crop on reading
        stream.width = width + (width % 2 if pad else 0)
        stream.height = height + (height % 2 if pad else 0)
        if (stream.width, stream.height) != (width, height):
            self._out.metadata[SIZE_TAG] = f"clpde size={width}x{height}"
        stream.pix_fmt = pix_fmt
        # AVI counts frames, not time: its time base is one frame.
        self._time_base = (
            1 / self.rate if self.format == "avi" or not self.like else self.like.time_base
        )
        cc.time_base = self._time_base
        stream.time_base = self._time_base
        if self.codec != "ffv1":
            cc.thread_count = 1
        stream.options = _encoder_options(self.codec, self.crf)
        colour = self.like.colour if self.like else {}
        rgb = self.codec == "ffv1"
        self._colour = {
            "space": 0 if rgb else (colour.get("space") or 1),
            "range": 2 if rgb else (colour.get("range") or 1),
        }
        cc.colorspace = self._colour["space"]
        cc.color_range = self._colour["range"]
        if colour.get("primaries"):
            cc.color_primaries = colour["primaries"]
        if colour.get("trc"):
            cc.color_trc = colour["trc"]
        if self.like is not None:
            stream.metadata.update(
                {k: v for k, v in self.like.video_metadata.items() if k in _STREAM_TAGS}
            )
        self._video = stream
        self._pix_fmt = pix_fmt

    def write(self, frame: np.ndarray, pts: int | None = None) -> None:
        """Encode one RGB frame (uint8, or uint16 for deep videos) at timestamp `pts`.

        Parameters
        ----------
        frame : ndarray
            (rows, columns, 3) RGB, or (rows, columns) grey; every frame of one size.
        pts : int, optional
            Its presentation time in the input's time base (default: the next frame's).

        Raises
        ------
        InputError
            For a frame of another dtype, shape or size than the first.
        """
        av = require_av()
        frame = _as_rgb(frame)
        if self._video is None:
            self._start(frame)
        if frame.shape[:2] != self.size:
            raise InputError(
                f"frame {self.count} is {frame.shape[1]}x{frame.shape[0]}, the film "
                f"{self.size[1]}x{self.size[0]}; all frames need one size"
            )
        stream = self._video
        if (stream.height, stream.width) != self.size:
            frame = np.pad(
                frame,
                ((0, stream.height - self.size[0]), (0, stream.width - self.size[1]), (0, 0)),
                mode="edge",
            )
        source = "rgb24" if frame.dtype == np.uint8 else "rgb48le"
        picture = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format=source)
        picture.color_range = 2  # RGB frames are full range
        picture = picture.reformat(
            format=self._pix_fmt,
            dst_colorspace=self._colour["space"] or None,
            dst_color_range=self._colour["range"],
        )
        if pts is None:
            pts = self.count
        elif self.like is not None and self._time_base != self.like.time_base:
            pts = round(pts * self.like.time_base / self._time_base)
        picture.pts = int(pts)
        picture.time_base = self._time_base
        if self._side is not None:
            self._side.mux_until(float(picture.pts * self._time_base))
        for packet in stream.encode(picture):
            self._out.mux(packet)
        self.count += 1

    def close(self) -> Path:
        """Flush the encoder and the side streams and put the video in place.

        Returns
        -------
        Path
            The written video.

        Raises
        ------
        InputError
            If no frame was written.
        """
        if self._video is None:
            self.abort()
            raise InputError(f"no frames to write to {self.path}")
        try:
            for packet in self._video.encode():
                self._out.mux(packet)
            if self._side is not None:
                self._side.mux_until(None)
            self._out.close()
            if self._side is not None:
                self._side.close()
        except BaseException:
            self.abort()
            raise
        self._atomic.__exit__(None, None, None)
        return self.path

    def abort(self) -> None:
        """Stop and leave nothing behind."""
        for closable in (getattr(self, "_out", None), self._side):
            if closable is not None:
                with contextlib.suppress(Exception):
                    closable.close()
        with contextlib.suppress(BaseException):
            self._atomic.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, kind, value, tb) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()


def write_video(
    path: PathLike, frames: Iterable[np.ndarray], rate: Fraction, *, codec: str | None = None
) -> Path:
    """Write frames as a new video at `rate` frames per second.

    Parameters
    ----------
    path : str or PathLike
        The video to write (.mp4, .mov, .mkv, .avi); written atomically.
    frames : iterable of ndarray
        (rows, columns[, 3]) uint8 or uint16 frames, all of one size.
    rate : Fraction
        Frames per second.
    codec : {'h264', 'h265', 'ffv1'}, optional
        The video codec (default h264).

    Returns
    -------
    Path
        The written video.

    Raises
    ------
    InputError
        As :class:`VideoWriter`; and no frames.

    Examples
    --------
    >>> write_video("clip.mp4", np.zeros((3, 16, 16, 3), np.uint8), 25)  # doctest: +SKIP
    PosixPath('clip.mp4')
    """
    with VideoWriter(path, rate, codec=codec) as writer:
        for frame in frames:
            writer.write(frame)
    return Path(path)
