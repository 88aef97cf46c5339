"""Films in and out (PyAV), the sliding window, and chunked runs on a real Dask LocalCluster.

The films are made here with PyAV: 32x24 px, 12 frames at 25 fps, a pan over a scikit-image
photo with dark blotches and a white scratch, an AAC audio stream and a mov_text subtitle.
The window work is real: a temporal fill (the mean of the neighbours that see a pixel clean,
clpde.inpaint where none does) and a spike detector, both reading one frame either side.
"""

from __future__ import annotations

import hashlib
from fractions import Fraction

import numpy as np
import pytest

av = pytest.importorskip("av")

import clpde  # noqa: E402
from clpde.film.restore import restore_film  # noqa: E402
from clpde.film.stream import (  # noqa: E402
    WindowWork,
    plan_blocks,
    restore_stream,
)
from clpde.imagedata import InputError  # noqa: E402
from clpde.io import read_image, write_image  # noqa: E402
from clpde.io.video import VideoReader, VideoWriter  # noqa: E402
from clpde.io.video_probe import video_info  # noqa: E402

T, H, W = 12, 24, 32


# ---- films made with PyAV -----------------------------------------------------------------
def clean_frames(count=T, height=H, width=W):
    """A pan over scikit-image's coffee photo, downscaled: one pixel a frame."""
    from skimage import data, transform

    photo = transform.resize(data.coffee(), (height * 2, width * 3), anti_aliasing=True)
    photo = (photo * 255).round().astype(np.uint8)
    return np.stack(
        [photo[height // 2 : height // 2 + height, t : t + width] for t in range(count)]
    )


def damage(frames, seed=0):
    """Dark blotches, a new set each frame, and a white scratch at column 20 in frames 3-8.
    Returns (damaged frames, true masks)."""
    rng = np.random.default_rng(seed)
    out, masks = frames.copy(), np.zeros(frames.shape[:3], bool)
    for t in range(len(frames)):
        for _ in range(2):
            y, x = rng.integers(2, frames.shape[1] - 4), rng.integers(2, frames.shape[2] - 4)
            masks[t, y : y + 3, x : x + 3] = True
        if 3 <= t <= 8:
            masks[t, 2:-2, 20] = True
    out[masks] = 0
    out[:, 2:-2, 20][masks[:, 2:-2, 20]] = 255
    return out, masks


def make_film(
    path,
    frames,
    *,
    audio=True,
    subtitles=True,
    pix_fmt="yuv420p",
    codec="libx264",
    rate=25,
    options=None,
    fmt=None,
):
    """Write `frames` (uint8 RGB, or uint16 for deep films) with an AAC tone and mov_text."""
    container = av.open(str(path), "w", format=fmt)
    video = container.add_stream(codec, rate=rate)
    video.width, video.height, video.pix_fmt = frames.shape[2], frames.shape[1], pix_fmt
    video.codec_context.colorspace, video.codec_context.color_range = 1, 1  # BT.709, TV range
    if options:
        video.options = options
    container.metadata["title"] = "a test film"
    if audio:
        sound = container.add_stream("aac", rate=8000)
        sound.layout = "mono"
    if subtitles:
        text = container.add_mux_stream("mov_text")
        text.time_base = Fraction(1, 1000)
    source = "rgb24" if frames.dtype == np.uint8 else "rgb48le"
    for t, frame in enumerate(frames):
        picture = av.VideoFrame.from_ndarray(frame, format=source).reformat(
            format=pix_fmt, dst_colorspace=1, dst_color_range=1
        )
        picture.pts = t
        for packet in video.encode(picture):
            container.mux(packet)
    if audio:
        n = len(frames) * 8000 // rate
        tone = (0.3 * np.sin(np.arange(n) * 2 * np.pi * 440 / 8000)).astype(np.float32)
        for k in range(0, n, 1024):
            chunk = av.AudioFrame.from_ndarray(
                tone[None, k : k + 1024].copy(), format="fltp", layout="mono"
            )
            chunk.sample_rate, chunk.pts = 8000, k
            for packet in sound.encode(chunk):
                container.mux(packet)
        for packet in sound.encode():
            container.mux(packet)
    if subtitles:
        for start, words in ((0, "dust"), (200, "and scratches")):
            data = words.encode()
            packet = av.Packet(len(data).to_bytes(2, "big") + data)
            packet.pts = packet.dts = start
            packet.duration, packet.time_base, packet.stream = 150, Fraction(1, 1000), text
            container.mux(packet)
    for packet in video.encode():
        container.mux(packet)
    container.close()
    return path


def packets(path, kind):
    """(bytes, seconds) of every non-empty packet of the streams of one kind."""
    with av.open(str(path)) as container:
        streams = [s for s in container.streams if s.type == kind]
        if not streams:
            return []
        return [(bytes(p), float(p.pts * p.time_base)) for p in container.demux(streams) if p.size]


def decoded(path):
    return np.stack(list(VideoReader(path)))


# ---- real window work ---------------------------------------------------------------------
def temporal_fill(frames, masks, channel_axis=None):
    """Each masked pixel from the mean of frames t-1 and t+1 where they see it clean; what no
    neighbour sees, by clpde.inpaint."""
    out = frames.copy()
    for t in range(len(frames)):
        if not masks[t].any():
            continue
        total = np.zeros(frames.shape[1:], np.float64)
        seen = np.zeros(masks.shape[1:], np.int32)
        for s in (t - 1, t + 1):
            if 0 <= s < len(frames):
                ok = ~masks[s]
                total[ok] += frames[s][ok]
                seen += ok
        use = masks[t] & (seen > 0)
        out[t][use] = (total[use] / seen[use, ...][..., None]).round().astype(frames.dtype)
        rest = masks[t] & (seen == 0)
        if rest.any():
            out[t] = clpde.inpaint(out[t], rest, channel_axis=channel_axis, max_steps=200)
    return out


def spike_detect(frames, channel_axis=None):
    """Pixels darker or brighter than both neighbouring frames by more than 60 grey levels
    (at the film's first and last frames, than the one neighbour), and pixels brighter than
    their left and right neighbours by as much (a one-pixel scratch)."""
    grey = (
        frames.astype(np.float32).mean(axis=-1)
        if channel_axis is not None
        else frames.astype(np.float32)
    )
    masks = np.zeros(grey.shape, bool)
    for t in range(len(grey)):
        d = [grey[t] - grey[s] for s in (t - 1, t + 1) if 0 <= s < len(grey)]
        masks[t] = np.all([x > 60 for x in d], axis=0) | np.all([x < -60 for x in d], axis=0)
    masks[:, :, 1:-1] |= (grey[:, :, 1:-1] - grey[:, :, :-2] > 60) & (
        grey[:, :, 1:-1] - grey[:, :, 2:] > 60
    )
    return masks, masks.astype(np.int8)


WORK = WindowWork(fill=temporal_fill, detect=spike_detect, fill_radius=1, detect_radius=1)


def spatial_fill(frames, masks, channel_axis=None):
    """clpde.inpaint frame by frame (the work before temporal filling existed)."""
    return np.stack(
        [
            clpde.inpaint(f, m, channel_axis=channel_axis, max_steps=200) if m.any() else f
            for f, m in zip(frames, masks, strict=True)
        ]
    )


SPATIAL = WindowWork(fill=spatial_fill)


@pytest.fixture(scope="module")
def film(tmp_path_factory):
    folder = tmp_path_factory.mktemp("film")
    damaged, masks = damage(clean_frames())
    path = make_film(folder / "dusty.mp4", damaged)
    maskdir = folder / "masks"
    maskdir.mkdir()
    for t, m in enumerate(masks):
        write_image(maskdir / f"m{t + 1}.png", m.astype(np.uint8) * 255)  # m2 before m10
    return path, maskdir, masks


# ---- the window ---------------------------------------------------------------------------
def test_blocks_cover_every_frame_once_with_their_context():
    blocks = plan_blocks(10, 3, 2)
    assert [(b.start, b.stop) for b in blocks] == [(0, 3), (3, 6), (6, 9), (9, 10)]
    assert [(b.first, b.last) for b in blocks] == [(0, 5), (1, 8), (4, 10), (7, 10)]


def test_window_results_do_not_depend_on_the_block_size():
    """The work reads one frame either side for detection and one for filling: with two
    frames of context a block's frames are those of the whole film at once."""
    damaged, _ = damage(clean_frames())
    whole = [r for r, _, _ in restore_stream(damaged, T, WORK, block=T)]
    for block in (1, 2, 5):
        assert all(
            np.array_equal(a, b)
            for a, (b, _, _) in zip(
                whole, restore_stream(damaged, T, WORK, block=block), strict=True
            )
        )


def test_sliding_window_holds_one_window():
    """Frames are pulled from the reader only as the window needs them."""
    damaged, _ = damage(clean_frames())
    pulled = []

    def reader():
        for t, frame in enumerate(damaged):
            pulled.append(t)
            yield frame

    out = restore_stream(reader(), T, WORK, block=2)
    next(out)  # frame 0 needs frames 0..3 (block 0..1, then 2 frames of context)
    assert pulled == [0, 1, 2, 3]


# ---- films in and out ---------------------------------------------------------------------
def test_mp4_keeps_audio_subtitles_timing_colour_and_metadata(tmp_path, film):
    source, maskdir, _ = film
    out = restore_film(source, tmp_path / "restored.mp4", mask=maskdir, work=SPATIAL).output
    assert packets(out, "audio") == packets(source, "audio")  # copied, packet for packet
    assert packets(out, "subtitle") == packets(source, "subtitle")
    assert [p for p, _ in packets(out, "subtitle") if len(p) > 2] == [
        b"\x00\x04dust",
        b"\x00\x0dand scratches",
    ]
    before, after = video_info(source), video_info(out)
    assert (after.frames, after.rate, after.width, after.height) == (T, 25, W, H)
    assert after.colour == before.colour and after.metadata["title"] == "a test film"
    with av.open(str(source)) as a, av.open(str(out)) as b:
        times = [[float(f.pts * f.time_base) for f in c.decode(video=0)] for c in (a, b)]
    assert times[0] == times[1]


def test_ffv1_is_lossless_outside_the_masks(tmp_path, film):
    source, maskdir, masks = film
    out = tmp_path / "restored.mkv"
    result = restore_film(
        source, out, mask=maskdir, grow=1, masks_out=tmp_path / "masks", codec="ffv1", work=SPATIAL
    )
    written = np.stack([read_image(tmp_path / "masks" / f"mask_{t:05d}.png") > 0 for t in range(T)])
    restored, original = decoded(out), decoded(source)
    assert video_info(out).pix_fmt == "bgr0"  # RGB, no chroma subsampling
    assert np.array_equal(restored[~written], original[~written])
    assert (restored[written] != original[written]).any()
    assert result.masked_pixels == written.sum()
    assert [p for p, _ in packets(out, "audio")] == [p for p, _ in packets(source, "audio")]
    # mov_text cannot go in Matroska: converted to SubRip, the same text
    assert [p for p, _ in packets(out, "subtitle")] == [b"dust", b"and scratches"]


def test_masks_out_are_numbered_in_frame_order_and_grown(tmp_path, film):
    source, maskdir, masks = film
    restore_film(
        source,
        tmp_path / "out.mp4",
        mask=maskdir,
        grow=1,
        masks_out=tmp_path / "masks",
        work=SPATIAL,
    )
    names = sorted(p.name for p in (tmp_path / "masks").iterdir())
    assert names == [f"mask_{t:05d}.png" for t in range(T)]
    from scipy import ndimage

    for t in range(T):
        expected = ndimage.binary_dilation(masks[t], ndimage.generate_binary_structure(2, 1))
        assert np.array_equal(read_image(tmp_path / "masks" / names[t]) > 0, expected)


def test_ten_bit_films_stay_ten_bit(tmp_path):
    frames = clean_frames(6).astype(np.uint16) * 257
    source = make_film(tmp_path / "deep.mp4", frames, pix_fmt="yuv420p10le", subtitles=False)
    masks = np.zeros((H, W), np.uint8)
    write_image(tmp_path / "m.png", masks)
    lossless = restore_film(
        source, tmp_path / "deep.mkv", mask=tmp_path / "m.png", codec="ffv1", work=SPATIAL
    ).output
    assert video_info(lossless).pix_fmt == "gbrp16le"
    assert np.array_equal(decoded(lossless), decoded(source))
    assert decoded(source).dtype == np.uint16
    h264 = restore_film(
        source, tmp_path / "deep_h264.mp4", mask=tmp_path / "m.png", work=SPATIAL
    ).output
    assert video_info(h264).pix_fmt == "yuv420p10le"


def test_interlaced_film_is_refused(tmp_path):
    source = make_film(
        tmp_path / "fields.mp4",
        clean_frames(4),
        audio=False,
        subtitles=False,
        options={"flags": "+ildct+ilme", "x264-params": "interlaced=1"},
    )
    with pytest.raises(InputError, match="interlaced"):
        restore_film(source, tmp_path / "out.mp4", mask=None, work=WORK)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fields.mp4"]


def test_the_cluster_opens_only_once_the_film_and_outputs_are_checked(tmp_path):
    """restore_film enters the cluster it is given (clpde restore --workers N's) after its
    checks: a bad output starts no Dask workers."""
    import contextlib

    opened = []

    @contextlib.contextmanager
    def cluster():
        opened.append(True)
        yield None, {}

    source = make_film(tmp_path / "in.mp4", clean_frames(4), audio=False, subtitles=False)
    with pytest.raises(InputError, match="is the input"):
        restore_film(source, source, cluster=cluster(), work=WORK)
    with pytest.raises(InputError, match="not both"):
        restore_film(source, tmp_path / "out.mp4", cluster=cluster(), client=object(), work=WORK)
    assert opened == []


def test_writer_keeps_the_given_timestamps(tmp_path):
    frames = clean_frames(4)
    with VideoWriter(tmp_path / "vfr.mkv", rate=25, codec="ffv1") as writer:
        for pts, frame in zip((0, 1, 5, 6), frames, strict=True):
            writer.write(frame, pts=pts)
    with av.open(str(tmp_path / "vfr.mkv")) as c:
        assert [round(float(f.time), 3) for f in c.decode(video=0)] == [0, 0.04, 0.2, 0.24]


def test_interrupt_leaves_nothing(tmp_path, film):
    source, maskdir, _ = film
    calls = []

    def interrupted(frames, masks, channel_axis=None):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return spatial_fill(frames, masks, channel_axis)

    work = WindowWork(fill=interrupted)
    with pytest.raises(KeyboardInterrupt):
        restore_film(
            source,
            tmp_path / "out.mkv",
            mask=maskdir,
            masks_out=tmp_path / "m",
            overlay=tmp_path / "o.mp4",
            block=4,
            work=work,
        )
    assert list(tmp_path.iterdir()) == []


def test_frame_folder_in_and_out(tmp_path, film):
    _, maskdir, masks = film
    damaged, _ = damage(clean_frames())
    frames = tmp_path / "frames"
    frames.mkdir()
    for t, frame in enumerate(damaged):
        write_image(frames / f"scan{t + 1}.png", frame)
    result = restore_film(frames, tmp_path / "out", mask=maskdir, work=WORK)
    assert result.frames == T
    expected = [r for r, _, _ in restore_stream(damaged, T, WORK, masks=iter(masks))]
    for t in range(T):
        assert np.array_equal(read_image(tmp_path / "out" / f"scan{t + 1}.png"), expected[t])


# ---- Dask ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    import sys

    import cloudpickle
    from distributed import Client

    from clpde.scale.cluster import start_cluster

    # The window work lives in this test module, which the workers cannot import by name.
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    # clpde's own cluster: a plain LocalCluster's nanny leaves MALLOC_TRIM_THRESHOLD_ in
    # this process's environment, which later clusters' workers would inherit
    cluster, _, _ = start_cluster(workers=2, threads=1)
    live = Client(cluster)
    yield live
    live.close()
    cluster.close()
    cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def test_chunked_run_on_dask_equals_one_process(tmp_path, client):
    """24 frames in blocks of 2 and chunks of 4 frames: 6 chunks, 5 boundaries, with the
    scratch of frames 3-8 across two of them (at frames 4 and 8)."""
    damaged, _ = damage(clean_frames(24))
    source = make_film(tmp_path / "long.mp4", damaged)
    one = restore_film(
        source, tmp_path / "one.mkv", codec="ffv1", block=2, masks_out=tmp_path / "m1", work=WORK
    )
    chunked = restore_film(
        source,
        tmp_path / "chunked.mkv",
        codec="ffv1",
        block=2,
        client=client,
        chunk_frames=4,
        masks_out=tmp_path / "m2",
        work=WORK,
    )
    assert chunked.workers == 2 and one.workers == 0
    assert chunked.frames_sha256 == one.frames_sha256
    assert np.array_equal(decoded(tmp_path / "one.mkv"), decoded(tmp_path / "chunked.mkv"))
    for t in range(24):
        name = f"mask_{t:05d}.png"
        assert (tmp_path / "m1" / name).read_bytes() == (tmp_path / "m2" / name).read_bytes()
    found = np.stack([read_image(tmp_path / "m1" / f"mask_{t:05d}.png") > 0 for t in range(24)])
    # the scratch, found (most of it, through H.264) in every frame it crosses
    assert (found[3:9, 4:-4, 20].mean(axis=1) > 0.7).all()
    digest = hashlib.sha256(decoded(tmp_path / "one.mkv").tobytes()).hexdigest()
    assert digest == chunked.frames_sha256  # lossless: the file holds those frames


def test_a_subtitle_the_container_cannot_take_is_dropped_with_a_warning(tmp_path, film):
    source, maskdir, _ = film
    with pytest.warns(
        UserWarning,
        match=r"subtitle stream 2 \(mov_text\) cannot go in a "
        r"\.avi file and was dropped; write \.mkv",
    ):
        out = restore_film(source, tmp_path / "out.avi", mask=maskdir, work=SPATIAL).output
    info = video_info(out)
    assert (info.frames, info.rate) == (T, 25)  # AVI counts frames: timestamps rescaled
    assert packets(out, "subtitle") == []
    assert [p for p, _ in packets(out, "audio")] == [p for p, _ in packets(source, "audio")]
