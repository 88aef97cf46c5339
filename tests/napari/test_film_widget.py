"""The film widget in a headless viewer: detect into Labels, restore, write back with sound."""

import numpy as np
import pytest
from qt_check import MISSING, WAIT_MS
from scipy import ndimage

if MISSING is not None:
    pytest.skip(MISSING, allow_module_level=True)

av = pytest.importorskip("av")

import clpde  # noqa: E402
from clpde.napari import readers  # noqa: E402
from clpde.napari.film import FilmWidget, detect_film  # noqa: E402


def make_film(path, frames, rate=10, audio=True):
    """A short H.264 film of `frames` (T, H, W, 3) uint8 with an AAC tone."""
    with av.open(str(path), "w") as out:
        video = out.add_stream("libx264", rate=rate)
        video.width, video.height, video.pix_fmt = frames.shape[2], frames.shape[1], "yuv420p"
        video.options = {"crf": "0"}
        sound = out.add_stream("aac", rate=44100) if audio else None
        for frame in frames:
            for packet in video.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")):
                out.mux(packet)
        for packet in video.encode():
            out.mux(packet)
        if sound is not None:
            t = np.arange(44100 * len(frames) // rate) / 44100
            tone = (0.2 * np.sin(2 * np.pi * 440 * t)).astype(np.float32)[None]
            for start in range(0, tone.shape[1], 1024):
                chunk = av.AudioFrame.from_ndarray(
                    np.ascontiguousarray(tone[:, start : start + 1024]),
                    format="fltp",
                    layout="mono",
                )
                chunk.sample_rate = 44100
                for packet in sound.encode(chunk):
                    out.mux(packet)
            for packet in sound.encode():
                out.mux(packet)


def audio_packets(path):
    with av.open(str(path)) as film:
        if not film.streams.audio:
            return []
        return [bytes(p) for p in film.demux(film.streams.audio[0]) if p.size]


@pytest.fixture
def dusty_film(tmp_path):
    rng = np.random.default_rng(0)
    # a smooth texture: grain-like noise does not survive the lossy codec, and the
    # detector trusts only motion it can check
    ground = ndimage.gaussian_filter(rng.random((48, 64)), 2.0)
    ground = ((ground - ground.min()) / np.ptp(ground) * 160 + 50).astype(np.uint8)
    frames = np.stack([np.roll(ground, t, axis=1) for t in range(8)])
    frames = np.repeat(frames[..., None], 3, axis=-1)
    for t in range(8):
        y, x = 10 + 3 * t, 20 + 4 * t % 40
        frames[t, y : y + 4, x : x + 4] = 0  # a new speck of dirt on every frame
    path = tmp_path / "dusty.mp4"
    make_film(path, frames)
    return path


def test_film_widget_detects_restores_and_writes_with_sound(
    make_napari_viewer, qtbot, dusty_film, tmp_path
):
    viewer = make_napari_viewer()
    ((data, attrs, kind),) = readers.read_film(str(dusty_film))
    film = viewer.add_image(data, **attrs)
    w = FilmWidget(viewer)
    w.film.value = film
    w.detect()
    qtbot.waitUntil(lambda: w.worker is None, timeout=WAIT_MS)
    defects = viewer.layers["dusty defects"].data
    expected = detect_film(data, -1, int(w.grow.value), lambda *_: None)
    np.testing.assert_array_equal(defects, expected)
    assert defects.any()
    w.run()
    qtbot.waitUntil(lambda: w.worker is None, timeout=WAIT_MS)
    restored = viewer.layers["dusty restored"].data
    np.testing.assert_array_equal(
        restored, clpde.inpaint_video(data, defects != 0, channel_axis=-1)
    )
    out = tmp_path / "restored.mkv"
    w.output.value = out
    w.write()
    qtbot.waitUntil(lambda: w.worker is None, timeout=WAIT_MS)
    assert out.is_file(), w.status.value
    assert audio_packets(out) == audio_packets(dusty_film)
    ((back, _, _),) = readers.read_film(str(out))
    np.testing.assert_array_equal(back, restored)  # FFV1 in Matroska is lossless
