"""`clpde restore`, `clpde inpaint FILM --mask`, `clpde batch restore` and the window, with
clpde's own detector and filler, on small films made with PyAV (32x24 px, 12 frames, AAC,
mov_text)."""

from __future__ import annotations

import numpy as np
import pytest

av = pytest.importorskip("av")

from clpde.cli import main  # noqa: E402
from clpde.io import read_image, write_image  # noqa: E402
from clpde.io.video_probe import video_info  # noqa: E402
from tests.film.test_film_io import (  # noqa: E402
    T,
    clean_frames,
    damage,
    decoded,
    make_film,
    packets,
)


@pytest.fixture
def film(tmp_path):
    damaged, masks = damage(clean_frames())
    source = make_film(tmp_path / "dusty.mp4", damaged)
    maskdir = tmp_path / "masks"
    maskdir.mkdir()
    for t, m in enumerate(masks):
        write_image(maskdir / f"m{t:02d}.png", m.astype(np.uint8) * 255)
    return source, maskdir


def _only(tmp_path, *names):
    return sorted(p.name for p in tmp_path.iterdir()) == sorted(names)


def test_inpaint_and_restore_with_masks_are_one_path(tmp_path, film, capsys):
    source, maskdir = film
    assert main(["inpaint", str(source), str(maskdir), "-o", str(tmp_path / "b.mp4")]) == 0
    assert (
        main(["restore", str(source), "--mask", str(maskdir), "-o", str(tmp_path / "a.mp4")]) == 0
    )
    assert (tmp_path / "a.mp4").read_bytes() == (tmp_path / "b.mp4").read_bytes()
    err = capsys.readouterr().err
    assert "restore: 12 frames" in err and "inpaint: 12 frames" in err
    # the per-frame report: the frames with most pixels filled, counted from the masks
    # (frames 3-8 carry the scratch as well as two blotches)
    listed = err.split("frames with most pixels filled: ")[1].splitlines()[0]
    frames = [int(part.split(" (")[0]) for part in listed.split(", ")]
    assert len(frames) == 5 and set(frames) <= set(range(3, 9))


def test_restore_detects_writes_masks_overlay_and_keeps_audio(tmp_path, film, capsys):
    source, _ = film
    out = tmp_path / "clean.mkv"
    status = main(
        [
            "restore",
            str(source),
            "-o",
            str(out),
            "--codec",
            "ffv1",
            "--grow",
            "1",
            "--masks-out",
            str(tmp_path / "found"),
            "--overlay",
            str(tmp_path / "overlay.mp4"),
        ]
    )
    assert status == 0, capsys.readouterr().err
    names = sorted(p.name for p in (tmp_path / "found").iterdir())
    assert names == [f"mask_{t:05d}.png" for t in range(T)]
    found = np.stack([read_image(tmp_path / "found" / n) > 0 for n in names])
    restored, original = decoded(out), decoded(source)
    assert np.array_equal(restored[~found], original[~found])  # lossless outside the masks
    assert [p for p, _ in packets(out, "audio")] == [p for p, _ in packets(source, "audio")]
    assert video_info(tmp_path / "overlay.mp4").frames == T


def test_bad_inputs_fail_with_one_line_and_write_nothing(tmp_path, film, capsys):
    source, maskdir = film
    out = tmp_path / "out.mp4"
    few = tmp_path / "few"
    few.mkdir()
    for t in range(3):
        write_image(few / f"m{t}.png", np.zeros((24, 32), np.uint8))
    write_image(tmp_path / "small.png", np.zeros((8, 8), np.uint8))
    sound_only = tmp_path / "sound.mp4"
    with av.open(str(sound_only), "w") as c:
        s = c.add_stream("aac", rate=8000)
        s.layout = "mono"
        frame = av.AudioFrame.from_ndarray(
            np.zeros((1, 1024), np.float32), format="fltp", layout="mono"
        )
        frame.sample_rate, frame.pts = 8000, 0
        for p in [*s.encode(frame), *s.encode()]:
            c.mux(p)
    (tmp_path / "afile").write_text("not a folder")
    before = sorted(p.name for p in tmp_path.iterdir())
    cases = [
        (["restore", str(source), "--mask", str(few), "-o", str(out)], "3 masks for 12 frames"),
        (["inpaint", str(source), "--mask", str(few), "-o", str(out)], "3 masks for 12 frames"),
        (
            ["restore", str(source), "--mask", str(tmp_path / "small.png"), "-o", str(out)],
            "same size",
        ),
        (["restore", str(sound_only), "-o", str(out)], "holds no video stream"),
        (["restore", str(source), "-o", str(tmp_path / "afile" / "out.mp4")], "does not exist"),
        (["restore", str(source), "-o", str(tmp_path / "nowhere" / "out.mp4")], "does not exist"),
        (["restore", str(source), "-o", str(out), "--codec", "ffv1"], "name the output .mkv"),
        (["restore", str(source), "-o", str(source)], "is the input"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("clpde: error:") and message in err and "\n" not in err, err
        assert sorted(p.name for p in tmp_path.iterdir()) == before, argv
    assert maskdir.is_dir()


def test_batch_restore_takes_many_films(tmp_path, capsys):
    films = []
    for k in range(2):
        damaged, _ = damage(clean_frames(6), seed=k)
        films.append(make_film(tmp_path / f"reel{k}.mp4", damaged, subtitles=False))
    status = main(
        [
            "batch",
            "restore",
            *map(str, films),
            "-o",
            str(tmp_path / "out"),
            "--workers",
            "2",
            "--threads",
            "1",
            "--grow",
            "1",
        ]
    )
    assert status == 0, capsys.readouterr().err
    for k in range(2):
        out = tmp_path / "out" / f"reel{k}.mp4"
        assert video_info(out).frames == 6
        assert packets(out, "audio") == packets(films[k], "audio")


def test_the_window_gives_the_whole_film_at_once():
    """Blocks of 4 frames, each with its context, give what clpde.detect_defects and
    clpde.inpaint_video (handed the detector's kinds, as `clpde restore` and the windows
    hand them on) give on all 16 frames at once: the context covers their reach."""
    import clpde
    from clpde.film.stream import KEEP, film_work, restore_stream

    damaged, _ = damage(clean_frames(16))
    masks, kinds = clpde.detect_defects(damaged, channel_axis=-1, grow=1, return_kinds=True)
    filled = clpde.inpaint_video(damaged, masks, channel_axis=-1, keep=KEEP, kinds=kinds)
    expected = np.where(masks[..., None], filled, damaged)
    streamed = list(restore_stream(damaged, 16, film_work(grow=1), block=4))
    assert masks.any()
    assert np.array_equal(np.stack([m for _, m, _ in streamed]), masks)
    assert np.array_equal(np.stack([k for _, _, k in streamed]), kinds)
    assert np.array_equal(np.stack([r for r, _, _ in streamed]), expected)


def test_the_windows_reuse_the_flows_they_share(monkeypatch):
    """The detector's flows are kept from one window to the next (clpde.film._motion's
    keep_flows): the windows estimate fewer flows and give the same frames, masks and kinds
    as without the memo, and nothing stays kept once the film has run."""
    from clpde.film import _motion, stream
    from clpde.film.stream import film_work, restore_stream
    from clpde.motion import dis

    damaged, _ = damage(clean_frames(16))
    estimated = []
    real = dis.DisFlow.flow

    def counted(self, a, b):
        estimated.append((a.shape, b.shape))
        return real(self, a, b)

    monkeypatch.setattr(dis.DisFlow, "flow", counted)
    runs, counts = [], []
    for kept in (0, stream.FLOWS_KEPT):
        monkeypatch.setattr(stream, "FLOWS_KEPT", kept)
        estimated.clear()
        runs.append(list(restore_stream(damaged, 16, film_work(), block=4)))
        counts.append(len(estimated))
        assert not _motion._memo.kept and not _motion._memo.sizes
    assert counts[1] < 0.8 * counts[0]
    for without, with_memo in zip(*runs, strict=True):
        assert all(np.array_equal(a, b) for a, b in zip(without, with_memo, strict=True))


def test_restore_on_two_dask_workers_equals_one_process(tmp_path, film, capsys):
    """clpde's own cluster (2 spawned workers, one PoCL thread each) in chunks of 4 frames
    against this process: the same lossless film and masks."""
    source, _ = film
    runs = {"one": [], "two": ["--workers", "2", "--chunk-frames", "4"]}
    for name, extra in runs.items():
        assert (
            main(
                [
                    "restore",
                    str(source),
                    "-o",
                    str(tmp_path / f"{name}.mkv"),
                    "--codec",
                    "ffv1",
                    "--masks-out",
                    str(tmp_path / f"m_{name}"),
                    *extra,
                ]
            )
            == 0
        )
    assert "2 Dask worker(s)" in capsys.readouterr().err
    assert np.array_equal(decoded(tmp_path / "one.mkv"), decoded(tmp_path / "two.mkv"))
    for t in range(T):
        name = f"mask_{t:05d}.png"
        assert (tmp_path / "m_one" / name).read_bytes() == (tmp_path / "m_two" / name).read_bytes()


def test_preview_writes_before_and_after_of_the_most_filled_frames(tmp_path, film, capsys):
    """--preview DIR: the 3 frames with most pixels filled, input left, output right."""
    source, maskdir = film
    out = tmp_path / "frames"
    status = main(
        [
            "restore",
            str(source),
            "--mask",
            str(maskdir),
            "-o",
            str(out),
            "--preview",
            str(tmp_path / "p"),
        ]
    )
    assert status == 0, capsys.readouterr().err
    pictures = sorted((tmp_path / "p").iterdir())
    assert len(pictures) == 3
    names = sorted(p.name for p in out.iterdir())
    for picture in pictures:
        t = int(picture.stem.split("_")[1])
        assert 3 <= t <= 8  # the frames with the scratch as well as blotches
        side = read_image(picture)
        restored = read_image(out / names[t])
        assert side.shape[1] == 2 * restored.shape[1]
        assert np.array_equal(side[:, restored.shape[1] :], restored)


def test_a_section_comes_out_as_in_the_whole_film(tmp_path, capsys):
    """--frames 10:14 of a 24-frame film: the frames around the section are its context
    (detection reads 3 frames either side, filling 2), so its frames and masks are those of
    the whole film's run, bit for bit; they keep their numbers, the film starts at time 0
    without sound, and a section outside the film is refused."""
    damaged, _ = damage(clean_frames(24))
    source = make_film(tmp_path / "long.mp4", damaged)
    whole, part = tmp_path / "whole.mkv", tmp_path / "part"
    masks = ["--masks-out", str(tmp_path / "m_whole")]
    assert main(["restore", str(source), "-o", str(whole), "--codec", "ffv1", *masks]) == 0
    argv = ["restore", str(source), "-o", str(part), "--frames", "10:14"]
    assert main([*argv, "--masks-out", str(tmp_path / "m_part")]) == 0
    err = capsys.readouterr().err
    assert "restore: 5 frames" in err
    names = [f"frame_{t:05d}.png" for t in range(10, 15)]
    assert sorted(p.name for p in part.iterdir()) == names
    section = np.stack([read_image(part / name) for name in names])
    expected = decoded(whole)[10:15]
    assert np.array_equal(section, expected)
    assert not np.array_equal(section, decoded(source)[10:15])  # something was restored
    for t in range(10, 15):
        name = f"mask_{t:05d}.png"
        assert (tmp_path / "m_part" / name).read_bytes() == (
            tmp_path / "m_whole" / name
        ).read_bytes()
    film = tmp_path / "part.mp4"
    assert main(["restore", str(source), "-o", str(film), "--frames", "20:23"]) == 0
    with av.open(str(film)) as c:
        assert [f.pts for f in c.decode(video=0)][0] == 0
        assert not [s for s in c.streams if s.type == "audio"]
    assert video_info(film).frames == 4
    capsys.readouterr()
    assert main(["restore", str(source), "-o", str(tmp_path / "x.mp4"), "--frames", "20:24"]) == 2
    err = capsys.readouterr().err.strip()
    assert "frames 20:24 are not within the film's 0:23" in err and "\n" not in err
    assert not (tmp_path / "x.mp4").exists()


def test_batch_passes_the_section_on():
    from clpde.cli.batch import command_options

    assert command_options("restore", ["--frames", "2:5"])["frames"] == (2, 5)
