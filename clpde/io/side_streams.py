"""The streams that travel with a video's pictures: audio and subtitles, carried from an input
file into the video that clpde.io.video's writer makes of it.

Audio streams are copied packet for packet (never re-encoded); a codec the output's
container cannot hold is refused before any work. Subtitle streams are copied where the
output's container takes them and converted otherwise (timed text between MP4's mov_text
and Matroska's SubRip), with a one-line warning for a stream that can go neither way. The
packets are muxed as the pictures are written, up to each picture's time, so that the file
is interleaved and only one packet is held at a time.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from ..errors import InputError

# Timed-text subtitles that carry the same text under another container's codec.
_TEXT_CONVERSIONS = {
    ("mov_text", "matroska"): "subrip",
    ("subrip", "mp4"): "mov_text",
    ("subrip", "mov"): "mov_text",
    ("text", "mp4"): "mov_text",
    ("text", "mov"): "mov_text",
    ("mov_text", "avi"): None,
}
_STREAM_TAGS = ("language", "title", "handler_name")


def _codec_name(stream) -> str:
    return stream.codec_context.name if stream.codec_context else stream.codec.name


class SideStreams:
    """The audio and subtitle streams of an input, added to an output container.

    Parameters
    ----------
    source : av container
        The input, opened for reading; closed by :meth:`close`.
    packets : iterator, optional
        The source's packets of the streams carried over (None: none are).
    streams : dict
        The output stream and the text conversion (source codec, target codec; None for a
        copy) of each carried input stream, by the input stream's index.
    out : av container
        The output, opened for writing.

    Examples
    --------
    >>> import av  # doctest: +SKIP
    >>> out = av.open("out.mkv", "w")  # doctest: +SKIP
    >>> side = SideStreams.copy("in.mp4", out, Path("out.mkv"), "matroska")  # doctest: +SKIP
    """

    def __init__(self, source, packets, streams: dict, out) -> None:
        self.source, self._packets, self._streams, self._out = source, packets, streams, out
        self._pending = None

    @classmethod
    def copy(cls, source: Path, out, path: Path, fmt: str) -> SideStreams | None:
        """Add the audio and subtitle streams of the file `source` to the container `out`.

        Parameters
        ----------
        source : Path
            The input file.
        out : av container
            The output, opened for writing, before its video stream is added.
        path : Path
            The output's file name, for messages.
        fmt : str
            The output's container format (``mp4``, ``matroska``, ...).

        Returns
        -------
        SideStreams or None
            The streams to mux as the pictures are written; None when there are none.

        Raises
        ------
        InputError
            For an audio stream that the output's container cannot hold.
        """
        import av

        side = av.open(str(source))
        supported = out.supported_codecs
        streams: dict = {}
        wanted = []
        try:
            for stream in side.streams:
                name = _codec_name(stream)
                if stream.type == "audio":
                    if name not in supported:
                        raise InputError(
                            f"{path}: the audio stream {stream.index} ({name}) "
                            f"cannot go in a {path.suffix} file; write .mkv"
                        )
                    added = out.add_stream_from_template(stream)
                    streams[stream.index] = (added, None)
                elif stream.type == "subtitle":
                    convert = None
                    if name not in supported:
                        convert = _TEXT_CONVERSIONS.get((name, fmt))
                        if convert is None or convert not in supported:
                            warnings.warn(
                                f"subtitle stream {stream.index} ({name}) cannot go in a "
                                f"{path.suffix} file and was dropped; write .mkv "
                                "to keep it",
                                stacklevel=3,
                            )
                            continue
                        added = out.add_mux_stream(convert)
                        added.time_base = stream.time_base
                    else:
                        added = out.add_stream_from_template(stream)
                    streams[stream.index] = (added, (name, convert) if convert else None)
                else:
                    continue
                added.metadata.update(
                    {k: v for k, v in stream.metadata.items() if k in _STREAM_TAGS}
                )
                wanted.append(stream)
        except BaseException:
            side.close()
            raise
        if not wanted:
            side.close()
            return None
        return cls(side, side.demux(*wanted), streams, out)

    def mux_until(self, until: float | None) -> None:
        """Mux the packets up to time `until` (seconds; None: all that are left).

        Parameters
        ----------
        until : float or None
            The time of the picture about to be written.
        """
        if self._packets is None:
            return
        while True:
            if self._pending is None:
                packet = next(self._packets, None)
                if packet is None:
                    self._packets = None
                    return
                if packet.size == 0 and packet.dts is None:
                    continue  # a demuxer's flush packet, not data
                self._pending = packet
            packet = self._pending
            when = packet.dts if packet.dts is not None else packet.pts
            if until is not None and when is not None and float(when * packet.time_base) > until:
                return
            self._pending = None
            out, convert = self._streams[packet.stream.index]
            if convert is not None:
                packet = _convert_text(packet, *convert)
            elif _codec_name(out) == "mov_text" and len(bytes(packet)) <= 2:
                packet = None  # MP4's muxer writes the gaps between texts itself
            if packet is None:
                continue
            packet.stream = out
            self._out.mux(packet)

    def close(self) -> None:
        """Close the input."""
        self.source.close()


def _convert_text(packet, source: str, target: str):
    """A timed-text packet's text under another codec: mov_text is a 2-byte big-endian
    length, the UTF-8 text, then style boxes (dropped); SubRip and plain text are the text."""
    import av

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
