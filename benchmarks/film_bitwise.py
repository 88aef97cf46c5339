"""The film path's files, frames and decoded pictures, saved for a bitwise check across a
refactor of clpde's video reading and writing.

    PYTHONPATH=<old tree> python benchmarks/film_bitwise.py save out/fbit/a
    PYTHONPATH=<new tree> python benchmarks/film_bitwise.py save out/fbit/b
    python benchmarks/film_bitwise.py compare out/fbit/a out/fbit/b

The input films are made here with PyAV alone (no clpde code): a small pan over scikit-image's
coffee photo with blotches and a scratch, H.264 with an AAC tone and a mov_text subtitle,
and a 10-bit one. Each is restored by ``restore_film`` into the outputs a user asks for
(FFV1 in Matroska, H.264 in MP4, 10-bit, AVI, a folder of PNGs, the masks and the overlay),
with clpde's own detector and filler once and a cheap window work otherwise; the check
compares the restored frames' digest, every output file's bytes (a Matroska file's by its
packets and tags: its muxer writes a random segment UID), every film's packets, and the
films read back by the frame readers (the tracker's `read_frames`, `read_video`). Files
whose name starts with ``picture_`` are pictures (the restoration's overlay and a film
written by `write_video`), which a change of the one video writer may change; the compare
lists them apart.

The script runs against either tree: where a function moved, it takes whichever spelling
the tree has.
"""

from __future__ import annotations

import hashlib
import importlib
import warnings
from fractions import Fraction
from pathlib import Path

import numpy as np
from bitwise import main

T, H, W = 10, 24, 32


def _first(*paths):
    """The first of 'module:name' that this tree has."""
    for path in paths:
        module, name = path.split(":")
        try:
            return getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError):
            continue
    raise ImportError(f"none of {paths}")


def _clean(count=T):
    from skimage import data, transform

    photo = transform.resize(data.coffee(), (H * 2, W * 3), anti_aliasing=True)
    photo = (photo * 255).round().astype(np.uint8)
    return np.stack([photo[H // 2 : H // 2 + H, t : t + W] for t in range(count)])


def _damage(frames):
    rng = np.random.default_rng(0)
    out, masks = frames.copy(), np.zeros(frames.shape[:3], bool)
    for t in range(len(frames)):
        y, x = rng.integers(2, H - 5), rng.integers(2, W - 5)
        masks[t, y : y + 3, x : x + 3] = True
        if 3 <= t <= 7:
            masks[t, 2:-2, 20] = True
    out[masks] = 0
    out[:, 2:-2, 20][masks[:, 2:-2, 20]] = 255
    return out, masks


def _make_film(path, frames, *, pix_fmt="yuv420p", sound=True, text=True):
    """A film written by PyAV alone: H.264, BT.709 TV range, an AAC tone, mov_text."""
    import av

    container = av.open(str(path), "w")
    video = container.add_stream("libx264", rate=25)
    video.width, video.height, video.pix_fmt = W, H, pix_fmt
    video.codec_context.colorspace, video.codec_context.color_range = 1, 1
    video.options = {"x264-params": "mbtree=0"}
    video.thread_count = 1
    container.metadata["title"] = "a bitwise film"
    if sound:
        audio = container.add_stream("aac", rate=8000)
        audio.layout = "mono"
    if text:
        subtitles = container.add_mux_stream("mov_text")
        subtitles.time_base = Fraction(1, 1000)
    source = "rgb24" if frames.dtype == np.uint8 else "rgb48le"
    for t, frame in enumerate(frames):
        picture = av.VideoFrame.from_ndarray(frame, format=source).reformat(
            format=pix_fmt, dst_colorspace=1, dst_color_range=1
        )
        picture.pts = t
        for packet in video.encode(picture):
            container.mux(packet)
    if sound:
        n = len(frames) * 8000 // 25
        tone = (0.3 * np.sin(np.arange(n) * 2 * np.pi * 440 / 8000)).astype(np.float32)
        for k in range(0, n, 1024):
            chunk = av.AudioFrame.from_ndarray(
                tone[None, k : k + 1024].copy(), format="fltp", layout="mono"
            )
            chunk.sample_rate, chunk.pts = 8000, k
            for packet in audio.encode(chunk):
                container.mux(packet)
        for packet in audio.encode():
            container.mux(packet)
    if text:
        for start, words in ((0, "dust"), (200, "and scratches")):
            data = words.encode()
            packet = av.Packet(len(data).to_bytes(2, "big") + data)
            packet.pts = packet.dts = start
            packet.duration, packet.time_base, packet.stream = 150, Fraction(1, 1000), subtitles
            container.mux(packet)
    for packet in video.encode():
        container.mux(packet)
    container.close()
    return path


def _temporal_fill(frames, masks, channel_axis=None):
    """Each masked pixel from the neighbours t - 1 and t + 1 that see it clean; else kept."""
    out = frames.copy()
    for t in range(len(frames)):
        total = np.zeros(frames.shape[1:], np.float64)
        seen = np.zeros(masks.shape[1:], np.int32)
        for s in (t - 1, t + 1):
            if 0 <= s < len(frames):
                total[~masks[s]] += frames[s][~masks[s]]
                seen += ~masks[s]
        use = masks[t] & (seen > 0)
        out[t][use] = (total[use] / seen[use][..., None]).round().astype(frames.dtype)
    return out


def _digest(path: Path) -> np.ndarray:
    return np.frombuffer(hashlib.sha256(path.read_bytes()).digest(), np.uint8)


def _packets(path: Path) -> np.ndarray:
    """SHA-256 over every packet of every stream (index, timestamps, bytes) and the tags:
    Matroska files differ run to run in their bytes (the muxer writes a random segment UID),
    so theirs are compared by content."""
    import av

    digest = hashlib.sha256()
    with av.open(str(path)) as container:
        digest.update(repr(sorted(container.metadata.items())).encode())
        for stream in container.streams:
            digest.update(
                repr((stream.index, stream.type, sorted(stream.metadata.items()))).encode()
            )
        for packet in container.demux():
            if packet.size:
                digest.update(repr((packet.stream.index, packet.pts, packet.dts)).encode())
                digest.update(bytes(packet))
    return np.frombuffer(digest.digest(), np.uint8)


def _film_digests(res: dict, name: str, path: Path) -> None:
    res[f"{name}_packets"] = _packets(path)
    if path.suffix != ".mkv":
        res[f"{name}_file"] = _digest(path)


def _film_reader(path):
    reader = _first("clpde.io.video:VideoReader", "clpde.film.container:FilmReader")
    return np.stack(list(reader(path)))


def save(out: Path) -> None:
    import clpde
    from clpde.film.restore import restore_film
    from clpde.film.stream import WindowWork
    from clpde.io import write_image

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    res: dict = {}
    damaged, masks = _damage(_clean())
    source = _make_film(out / "in_dusty.mp4", damaged)
    deep = _make_film(
        out / "in_deep.mp4", _clean(6).astype(np.uint16) * 257, pix_fmt="yuv420p10le", text=False
    )
    maskdir = out / "in_masks"
    maskdir.mkdir(exist_ok=True)
    for t, m in enumerate(masks):
        write_image(maskdir / f"m{t + 1}.png", m.astype(np.uint8) * 255)
    work = WindowWork(fill=_temporal_fill, fill_radius=1)
    runs = {
        # clpde's own detector and filler, lossless, with the masks and the overlay
        "detected_ffv1": dict(
            source=source,
            output=out / "detected.mkv",
            codec="ffv1",
            grow=1,
            masks_out=out / "detected_masks",
            overlay=out / "picture_overlay.mp4",
            block=4,
        ),
        "given_h264": dict(source=source, output=out / "given.mp4", mask=maskdir, work=work),
        "given_h265_mkv": dict(
            source=source, output=out / "given.mkv", mask=maskdir, codec="h265", work=work
        ),
        "given_avi": dict(source=source, output=out / "given.avi", mask=maskdir, work=work),
        "given_folder": dict(source=source, output=out / "given_frames", mask=maskdir, work=work),
        "deep_ffv1": dict(
            source=deep, output=out / "deep.mkv", mask=maskdir / "m1.png", codec="ffv1", work=work
        ),
        "deep_h264": dict(source=deep, output=out / "deep.mp4", mask=maskdir / "m1.png", work=work),
    }
    for name, options in runs.items():
        result = restore_film(**options, progress=False)
        res[f"{name}_frames_sha256"] = np.frombuffer(bytes.fromhex(result.frames_sha256), np.uint8)
        res[f"{name}_masked"] = np.array([result.masked_pixels, result.frames])
        output = Path(options["output"])
        if output.is_dir():
            for f in sorted(output.iterdir()):
                res[f"{name}_file_{f.name}"] = _digest(f)
        else:
            _film_digests(res, name, output)
            res[f"{name}_decoded"] = _film_reader(output)
    for f in sorted((out / "detected_masks").iterdir()):
        res[f"detected_ffv1_mask_{f.stem}"] = _digest(f)
    _film_digests(res, "picture_overlay", out / "picture_overlay.mp4")
    # the frame readers: the film reader, read_video and the tracker's read_frames
    read_video = _first("clpde.io.video:read_video")
    read_frames = _first("clpde.io.frames:read_frames")
    for name, path in (("dusty", source), ("deep", deep)):
        res[f"reader_{name}"] = _film_reader(path)
    frames, rate = read_video(source)
    res["read_video_dusty"], res["read_video_rate"] = (
        frames,
        np.array([rate.numerator, rate.denominator]),
    )
    res["read_frames_grey"] = read_frames(source)
    res["read_frames_colour"] = read_frames(source, grey=False)
    # a film written by write_video (a picture: the tracker's overlay), read back
    write_video = _first("clpde.io.video:write_video")
    written = write_video(out / "picture_written.mp4", damaged, 10)
    _film_digests(res, "picture_written", written)
    res["picture_written_read"] = read_frames(written, grey=False)
    for name, value in res.items():
        np.save(out / f"{name}.npy", np.asarray(value))


def compare(a: Path, b: Path) -> int:
    differ = {False: 0, True: 0}
    counts = {False: 0, True: 0}
    for p in sorted(a.glob("*.npy")):
        x, y = np.load(p), np.load(b / p.name)
        same = x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        picture = p.stem.startswith("picture_")
        counts[picture] += 1
        differ[picture] += not same
        print(f"{p.stem:40s} {str(x.dtype):8s} {str(x.shape):18s} bitwise equal: {same}")
    print(
        f"film path: {counts[False] - differ[False]}/{counts[False]} identical; "
        f"pictures (may change): {counts[True] - differ[True]}/{counts[True]} identical"
    )
    return differ[False]


if __name__ == "__main__":
    main(save, __doc__, compare)
