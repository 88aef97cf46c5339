"""Films in and out through PyAV: frames decoded to RGB, the other streams carried over.

A film is read as RGB frames: 8-bit inputs as (rows, columns, 3) uint8, deeper ones (10-bit
and up) as uint16 over the full 16-bit range. Decoding uses the film's own colour matrix
and range, so the frames are what a player shows.

A restored film is written with the frames' timestamps, the frame rate, the colour matrix,
range, primaries and transfer, and the metadata of the input; its audio streams are copied
packet for packet, its subtitle streams copied where the output's container takes them and
converted otherwise (timed text between MP4's mov_text and Matroska's SubRip), with a
one-line warning for a stream that can go neither way. Codecs:

- ``h264`` (default) and ``h265``: 4:2:0, 10-bit where the input has more than 8 bits;
- ``ffv1``: lossless, in Matroska, storing the RGB planes (8- or 16-bit), so that the
  written film decodes to exactly the RGB frames that were given to it.

Interlaced input (frames made of two fields) is refused with one line: restoring it frame
by frame would mix two instants. Writes are atomic: the file appears only when complete.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.images import PathLike, atomic_output

FORMATS = {".mp4": "mp4", ".m4v": "mp4", ".mov": "mov", ".mkv": "matroska", ".avi": "avi"}
READ_SUFFIXES = set(FORMATS) | {".webm", ".mpg", ".mpeg", ".ogv", ".ts", ".mxf"}
CODECS = {"h264": "libx264", "h265": "libx265", "ffv1": "ffv1"}
LOSSLESS = ("ffv1",)
# clpde's video writer pads odd sizes for 4:2:0 and keeps the true size in this tag.
_SIZE_TAG = "comment"
_SIZE_RE = re.compile(r"clpde size=(\d+)x(\d+)")
# Container metadata the muxer writes itself: copying it would record the input's muxer.
_OWN_TAGS = {"major_brand", "minor_version", "compatible_brands", "encoder", "creation_time"}
# Timed-text subtitles that carry the same text under another container's codec.
_TEXT_CONVERSIONS = {
    ("mov_text", "matroska"): "subrip",
    ("subrip", "mp4"): "mov_text",
    ("subrip", "mov"): "mov_text",
    ("text", "mp4"): "mov_text",
    ("text", "mov"): "mov_text",
    ("mov_text", "avi"): None,
}


def _av():
    try:
        import av
    except ImportError:
        raise InputError('films need PyAV: pip install "clpde[batch]"') from None
    return av


def is_film(path: PathLike) -> bool:
    """Whether `path` names a film file (by its extension)."""
    return Path(path).suffix.lower() in READ_SUFFIXES


# ---- reading ------------------------------------------------------------------------------
@dataclass
class FilmInfo:
    """What a film's video stream is, and the streams that travel with it.

    Attributes
    ----------
    path : Path
        The film.
    frames : int
        The number of video frames (counted from the packets).
    rate : Fraction
        Frames per second.
    time_base : Fraction
        The unit of the video stream's timestamps.
    width, height : int
        The frames' size (before any padding clpde's writer added for 4:2:0).
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
        """The frames' dtype: uint8 for 8-bit films, uint16 for deeper ones."""
        return np.dtype(np.uint8 if self.depth <= 8 else np.uint16)


@contextlib.contextmanager
def _open(path: PathLike):
    av = _av()
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


def _size(container, stream) -> tuple[int, int]:
    width, height = stream.codec_context.width, stream.codec_context.height
    match = _SIZE_RE.search(container.metadata.get(_SIZE_TAG, ""))
    if match and int(match.group(1)) <= width and int(match.group(2)) <= height:
        return int(match.group(1)), int(match.group(2))
    return width, height


def film_info(path: PathLike) -> FilmInfo:
    """Read a film's description, and refuse what clpde cannot restore.

    Parameters
    ----------
    path : str or PathLike
        The film.

    Returns
    -------
    FilmInfo
        Its frame count, rate, size, depth, colour and metadata.

    Raises
    ------
    InputError
        If the film does not exist, cannot be read, holds no video stream or no frames, or
        is interlaced.

    Examples
    --------
    >>> film_info("film.mp4").frames  # doctest: +SKIP
    3000
    """
    av = _av()
    with _open(path) as container:
        stream = container.streams.video[0]
        cc = stream.codec_context
        width, height = _size(container, stream)
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
    depth = max(c.bits for c in fmt.components)
    colour = {
        "range": int(first.color_range),
        "space": int(first.colorspace),
        "primaries": int(first.color_primaries),
        "trc": int(first.color_trc),
    }
    return FilmInfo(
        Path(path),
        count,
        Fraction(rate),
        Fraction(stream.time_base),
        width,
        height,
        fmt.name,
        depth,
        colour,
        dict(container.metadata),
        dict(stream.metadata),
    )


def _to_rgb(frame, info: FilmInfo) -> np.ndarray:
    target = "rgb24" if info.depth <= 8 else "rgb48le"
    if frame.format.name in ("rgb24", "rgb48le") and frame.format.name == target:
        rgb = frame
    else:
        rgb = frame.reformat(
            format=target, src_color_range=frame.color_range or None, dst_color_range="JPEG"
        )
    # A copy of its own: PyAV's array shares the frame's buffer.
    return np.array(rgb.to_ndarray()[: info.height, : info.width])


class FilmReader:
    """A film's frames, decoded one at a time in display order, with their timestamps.

    Parameters
    ----------
    path : str or PathLike
        The film.

    Attributes
    ----------
    info : FilmInfo
        The film's description.
    timestamps : list of int
        The presentation timestamps of the frames read so far that the writer has not yet
        taken (in ``info.time_base``); :class:`FilmWriter` pops them in order.

    Examples
    --------
    >>> for frame in FilmReader("film.mp4"):  # doctest: +SKIP
    ...     print(frame.shape, frame.dtype)
    """

    def __init__(self, path: PathLike) -> None:
        self.info = film_info(path)
        self.timestamps: list[int] = []

    def __len__(self) -> int:
        return self.info.frames

    def __iter__(self) -> Iterator[np.ndarray]:
        av = _av()
        with _open(self.info.path) as container:
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


# ---- writing ------------------------------------------------------------------------------
def check_film_output(path: PathLike, codec: str | None = None) -> tuple[str, str]:
    """Check, before any work, that a film can be written at `path` with `codec`.

    Parameters
    ----------
    path : str or PathLike
        The film to write.
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
    >>> check_film_output("out.mkv", "ffv1")
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


def _pixel_format(codec: str, depth: int, dtype: np.dtype) -> str:
    if codec == "ffv1":
        return "bgr0" if dtype == np.uint8 else "gbrp16le"
    return "yuv420p" if depth <= 8 else "yuv420p10le"


class FilmWriter:
    """Restored frames into a film that keeps the input's timing, colour, sound and text.

    Parameters
    ----------
    path : str or PathLike
        The film to write (.mp4, .mov, .mkv, .avi); it appears only when :meth:`close`
        succeeds.
    like : FilmInfo, optional
        The input film: its timestamps' unit, rate, colour description and metadata are
        kept, and its audio and subtitle streams copied. None: a new film at `rate`.
    codec : {'h264', 'h265', 'ffv1'}, optional
        The video codec (default h264; ffv1 is lossless, in Matroska only).
    rate : Fraction, optional
        Frames per second when there is no `like` (default 25).
    crf : int
        The quality of h264 and h265 (lower is better).
    copy_streams : bool
        Copy `like`'s audio and subtitle streams (default True).

    Raises
    ------
    InputError
        See :func:`check_film_output`; and an audio stream that the container cannot hold.

    Examples
    --------
    >>> reader = FilmReader("in.mp4")  # doctest: +SKIP
    >>> with FilmWriter("out.mkv", like=reader.info, codec="ffv1") as writer:  # doctest: +SKIP
    ...     for frame in reader:
    ...         writer.write(frame, pts=reader.timestamps.pop(0))
    """

    def __init__(
        self,
        path: PathLike,
        like: FilmInfo | None = None,
        *,
        codec: str | None = None,
        rate: Fraction | None = None,
        crf: int = 17,
        copy_streams: bool = True,
    ) -> None:
        av = _av()
        self.path = Path(path)
        self.format, self.codec = check_film_output(self.path, codec)
        self.like, self.crf, self.count = like, crf, 0
        self.rate = Fraction(rate) if rate else (like.rate if like else Fraction(25))
        self._atomic = atomic_output(self.path)
        self._tmp = self._atomic.__enter__()
        self._side = self._side_packets = self._pending = None
        self._map: dict[int, tuple] = {}
        try:
            self._out = av.open(str(self._tmp), mode="w", format=self.format)
            self._video = None
            if like is not None:
                for key, value in like.metadata.items():
                    if key not in _OWN_TAGS and not (key == _SIZE_TAG and _SIZE_RE.search(value)):
                        self._out.metadata[key] = value
                if copy_streams:
                    self._add_side_streams(av)
        except BaseException:
            self.abort()
            raise

    # -- the streams that travel with the pictures
    def _add_side_streams(self, av) -> None:
        side = av.open(str(self.like.path))
        self._side = side
        supported = self._out.supported_codecs
        wanted = []
        for stream in side.streams:
            name = stream.codec_context.name if stream.codec_context else stream.codec.name
            if stream.type == "audio":
                if name not in supported:
                    raise InputError(
                        f"{self.path}: the audio stream {stream.index} ({name}) "
                        f"cannot go in a {self.path.suffix} file; write .mkv"
                    )
                out = self._out.add_stream_from_template(stream)
                self._map[stream.index] = (out, None)
            elif stream.type == "subtitle":
                convert = None
                if name not in supported:
                    convert = _TEXT_CONVERSIONS.get((name, self.format))
                    if convert is None or convert not in supported:
                        warnings.warn(
                            f"subtitle stream {stream.index} ({name}) cannot go in a "
                            f"{self.path.suffix} file and was dropped; write .mkv "
                            "to keep it",
                            stacklevel=3,
                        )
                        continue
                    out = self._out.add_mux_stream(convert)
                    out.time_base = stream.time_base
                else:
                    out = self._out.add_stream_from_template(stream)
                self._map[stream.index] = (out, (name, convert) if convert else None)
            else:
                continue
            out.metadata.update(
                {
                    k: v
                    for k, v in stream.metadata.items()
                    if k in ("language", "title", "handler_name")
                }
            )
            wanted.append(stream)
        if wanted:
            self._side_packets = side.demux(*wanted)
        else:
            side.close()
            self._side = None

    def _mux_side(self, until: float | None) -> None:
        """Mux the side streams' packets up to time `until` (seconds; None: all), so that the
        file is interleaved as it is written and only one packet is held at a time."""
        if self._side_packets is None:
            return
        while True:
            if self._pending is None:
                packet = next(self._side_packets, None)
                if packet is None:
                    self._side_packets = None
                    return
                if packet.size == 0 and packet.dts is None:
                    continue  # a demuxer's flush packet, not data
                self._pending = packet
            packet = self._pending
            when = packet.dts if packet.dts is not None else packet.pts
            if until is not None and when is not None and float(when * packet.time_base) > until:
                return
            self._pending = None
            out, convert = self._map[packet.stream.index]
            if convert is not None:
                packet = _convert_text(packet, *convert)
            elif self._map_codec(out) == "mov_text" and len(bytes(packet)) <= 2:
                packet = None  # MP4's muxer writes the gaps between texts itself
            if packet is None:
                continue
            packet.stream = out
            self._out.mux(packet)

    @staticmethod
    def _map_codec(stream) -> str:
        return stream.codec_context.name if stream.codec_context else stream.codec.name

    # -- the pictures
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
            self._out.metadata[_SIZE_TAG] = f"clpde size={width}x{height}"
        stream.pix_fmt = pix_fmt
        # AVI counts frames, not time: its time base is one frame.
        self._time_base = (
            1 / self.rate if self.format == "avi" or not self.like else self.like.time_base
        )
        cc.time_base = self._time_base
        stream.time_base = self._time_base
        options = {}
        if self.codec == "h264":
            # x264's macroblock-tree reads memory it never initialised: the same frames
            # would give other bytes run after run (one thread, for the same reason).
            options = {"crf": str(self.crf), "x264-params": "mbtree=0"}
            cc.thread_count = 1
        elif self.codec == "h265":
            options = {"crf": str(self.crf), "x265-params": "log-level=error"}
            cc.thread_count = 1
        else:
            options = {"level": "3", "slicecrc": "1", "g": "1"}
        stream.options = options
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
                {
                    k: v
                    for k, v in self.like.video_metadata.items()
                    if k in ("language", "title", "handler_name")
                }
            )
        self._video = stream
        self._pix_fmt = pix_fmt

    def write(self, frame: np.ndarray, pts: int | None = None) -> None:
        """Encode one RGB frame (uint8, or uint16 for deep films) at timestamp `pts`.

        Parameters
        ----------
        frame : ndarray
            (rows, columns, 3) RGB, or (rows, columns) grey; every frame of one size.
        pts : int, optional
            Its presentation time in the input's time base (default: the next frame's).
        """
        av = _av()
        frame = np.asarray(frame)
        if frame.ndim == 2:
            frame = np.repeat(frame[..., np.newaxis], 3, axis=-1)
        if (
            frame.dtype not in (np.uint8, np.uint16)
            or frame.ndim != 3
            or frame.shape[-1] not in (3, 4)
        ):
            raise InputError(
                f"film frames must be 8- or 16-bit grey or RGB, not {frame.dtype} "
                f"of shape {frame.shape}"
            )
        frame = frame[..., :3]
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
        if self.like is not None and self._side_packets is not None:
            self._mux_side(float(picture.pts * self._time_base))
        for packet in stream.encode(picture):
            self._out.mux(packet)
        self.count += 1

    def close(self) -> Path:
        """Flush the encoder and the side streams and put the film in place.

        Returns
        -------
        Path
            The written film.
        """
        if self._video is None:
            self.abort()
            raise InputError(f"no frames to write to {self.path}")
        try:
            for packet in self._video.encode():
                self._out.mux(packet)
            self._mux_side(None)
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
        for container in (getattr(self, "_out", None), self._side):
            if container is not None:
                with contextlib.suppress(Exception):
                    container.close()
        with contextlib.suppress(BaseException):
            self._atomic.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)

    def __enter__(self) -> FilmWriter:
        return self

    def __exit__(self, kind, value, tb) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()


def _convert_text(packet, source: str, target: str):
    """A timed-text packet's text under another codec: mov_text is a 2-byte big-endian
    length, the UTF-8 text, then style boxes (dropped); SubRip and plain text are the text."""
    av = _av()
    data = bytes(packet)
    if source == "mov_text":
        length = int.from_bytes(data[:2], "big") if len(data) >= 2 else 0
        text = data[2 : 2 + length]
        if not text:
            return None  # mov_text's empty samples mark gaps, which SubRip leaves implicit
    else:
        text = data
    if target == "mov_text":
        text = text.replace(b"\r\n", b"\n")
        text = len(text).to_bytes(2, "big") + text
    out = av.Packet(text)
    out.pts, out.dts, out.duration = packet.pts, packet.dts, packet.duration
    out.time_base = packet.time_base
    return out
