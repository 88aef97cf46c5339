"""A long PAL film restored with bounded memory, in one process and on 2 Dask workers.

    python benchmarks/film_long.py [--lengths 150,300] [--full] [--work film|spatial]
                                   [--source pan|corpus] [--clip-frames 24]
                                   [--block 16] [--chunk-frames 64] [--json PATH]

The 2-minute PAL film of issue 34, on the corpus, through ``clpde restore``'s defaults:

    python benchmarks/film_long.py --source corpus --lengths 3000 --modes one --block 32

The film is made here: 720x576 at 25 fps, H.264 with an AAC tone, from one of two sources
(--source):

- ``pan`` (the default): a pan (bouncing, 1-2 px a frame, with a slow vertical drift) over a
  panorama of three scikit-image photos (coffee, chelsea, astronaut), with damage: 12
  blotches a PAL frame, the same density at other sizes (dark and bright, 1-6 px radius,
  soft edges, 35-100 % opacity) and a 2-px vertical scratch that drifts and is present 50
  frames out of 100. It is generated frame by frame, never held whole.
- ``corpus`` (issue 34's long film): real footage, the clips of benchmarks/film_corpus.py
  (both halves), --clip-frames frames of each from the clip's first frame, read at the
  source film's own size, scaled to fit the frame (aspect kept) and centred on black bars,
  with the corpus's grain, flicker and damage drawn on the picture (film_corpus.make_clip's
  generator and seeds);
  the clips follow each other (a cut between them) and the sequence repeats to the length
  asked. The damaged clips are held while the film is written (about 250 MB at PAL).

For each length (frames), ``clpde restore FILM -o OUT.mp4`` runs (through
clpde.film.restore.restore_film) in a fresh process:

- ``one``: this process alone (PoCL with every core);
- ``dask``: a LocalCluster of 2 workers x 1 PoCL thread, started before the clock; the
  client reads and writes, the workers restore chunks.

Reported: frames per second, peak resident memory (VmHWM) of the process and of each Dask
worker, and the speed-up of 2 workers. Memory flat in length is shown by two lengths; the
2-minute film (3000 frames) is run with --full, else its time is extrapolated from the
throughput and said to be. ``--work spatial`` fills given masks frame by frame with
clpde.inpaint (no detection) to time the streaming and I/O alone. On a shared machine the
wall time says more about the other jobs: ``one`` also reports the CPU seconds of the
calling thread (reading, writing and the restoration's serial steps) and film_speed.py's
estimate of the cores the run keeps busy given two free ones.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "film_long.json"
WIDTH, HEIGHT, RATE = 720, 576, 25


# ---- the film -----------------------------------------------------------------------------
def panorama() -> np.ndarray:
    from skimage import data, transform

    parts = []
    for photo in (data.coffee(), data.chelsea(), data.astronaut()):
        scale = (HEIGHT + 64) / photo.shape[0]
        size = (HEIGHT + 64, int(round(photo.shape[1] * scale)))
        parts.append((transform.resize(photo, size, anti_aliasing=True) * 255).astype(np.uint8))
    return np.concatenate(parts, axis=1)


def clean_frame(pano: np.ndarray, t: int) -> np.ndarray:
    span = pano.shape[1] - WIDTH
    x = int(1.5 * t) % (2 * span)
    x = x if x <= span else 2 * span - x  # bounce at the ends
    y = int(32 + 30 * np.sin(t / 90))
    return pano[y : y + HEIGHT, x : x + WIDTH]


def damage(frame: np.ndarray, t: int, rng) -> tuple[np.ndarray, np.ndarray]:
    out = frame.astype(np.float32)
    mask = np.zeros(frame.shape[:2], bool)
    yy, xx = np.mgrid[-8:9, -8:9]
    for _ in range(max(1, round(12 * WIDTH * HEIGHT / (720 * 576)))):  # the density of PAL's 12
        r = rng.uniform(1, 6)
        y, x = rng.integers(10, HEIGHT - 10), rng.integers(10, WIDTH - 10)
        soft = np.clip((r + 1 - np.hypot(yy, xx)) / 2, 0, 1) * rng.uniform(0.35, 1.0)
        value = 15.0 if rng.random() < 0.6 else 240.0
        patch = out[y - 8 : y + 9, x - 8 : x + 9]
        patch += soft[..., None] * (value - patch)
        mask[y - 8 : y + 9, x - 8 : x + 9] |= soft > 0.05
    if (t // 50) % 2 == 0:
        col = int(WIDTH * (0.42 + 0.055 * np.sin(t / 40)))
        out[:, col : col + 2] = np.minimum(out[:, col : col + 2] + 70, 255)
        mask[:, col : col + 2] = True
    return out.round().astype(np.uint8), mask


def _fit(frame: np.ndarray) -> np.ndarray:
    """A frame scaled to fit WIDTH x HEIGHT, its aspect kept."""
    import cv2

    h, w = frame.shape[:2]
    scale = min(WIDTH / w, HEIGHT / h)
    size = (min(WIDTH, round(w * scale)), min(HEIGHT, round(h * scale)))
    how = cv2.INTER_AREA if scale < 1 else cv2.INTER_CUBIC
    return cv2.resize(frame, size, interpolation=how)


def corpus_clips(count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The corpus's clips as (damaged frames (T, HEIGHT, WIDTH, 3) uint8, true masks), each
    of `count` frames scaled to fit and centred on black bars; grain, flicker and damage
    drawn on the picture alone, by film_corpus's generator with make_clip's seeds."""
    from film_corpus import CALIBRATION, TEST, damage_clip, grain_flicker, read_clip

    clips = []
    for name, source, start, _ in CALIBRATION + TEST:
        rng = np.random.default_rng([0, sum(map(ord, name))])
        picture = np.stack([_fit(f) for f in read_clip(source, start, count)])
        dirty, truth, _ = damage_clip(grain_flicker(picture, rng), rng)
        _, h, w, _ = picture.shape
        y, x = (HEIGHT - h) // 2, (WIDTH - w) // 2
        frames = np.zeros((count, HEIGHT, WIDTH, 3), np.uint8)
        masks = np.zeros((count, HEIGHT, WIDTH), bool)
        frames[:, y : y + h, x : x + w] = dirty
        masks[:, y : y + h, x : x + w] = truth > 0
        clips.append((frames, masks))
    return clips


def film_frames(frames: int, source: str, clip_frames: int):
    """(frame, true mask) of the damaged film in order, from the pan or the corpus."""
    if source == "corpus":
        clips = corpus_clips(clip_frames)
        for t in range(frames):
            frames_of, masks_of = clips[(t // clip_frames) % len(clips)]
            yield frames_of[t % clip_frames], masks_of[t % clip_frames]
        return
    pano = panorama()
    rng = np.random.default_rng(2026)
    for t in range(frames):
        yield damage(clean_frame(pano, t), t, rng)


def make_film(
    path: Path,
    frames: int,
    mask_dir: Path | None = None,
    source: str = "pan",
    clip_frames: int = 24,
) -> None:
    """The damaged film (and, for --work spatial, its true masks as PNGs)."""
    import av

    from clpde.io import write_image

    with av.open(str(path), "w") as out:
        video = out.add_stream("libx264", rate=RATE)
        video.width, video.height, video.pix_fmt = WIDTH, HEIGHT, "yuv420p"
        video.options = {"crf": "18", "preset": "veryfast"}
        sound = out.add_stream("aac", rate=48000)
        sound.layout = "stereo"
        samples = 0
        for t, (frame, mask) in enumerate(film_frames(frames, source, clip_frames)):
            if mask_dir is not None:
                write_image(mask_dir / f"m{t:05d}.png", mask.astype(np.uint8) * 255)
            picture = av.VideoFrame.from_ndarray(frame, format="rgb24")
            picture.pts = t
            for packet in video.encode(picture):
                out.mux(packet)
            while samples < (t + 1) * 48000 // RATE:
                tone = 0.2 * np.sin((samples + np.arange(1024)) * 2 * np.pi * 220 / 48000)
                chunk = av.AudioFrame.from_ndarray(
                    np.stack([tone, tone]).astype(np.float32), format="fltp", layout="stereo"
                )
                chunk.sample_rate, chunk.pts = 48000, samples
                for packet in sound.encode(chunk):
                    out.mux(packet)
                samples += 1024
        for stream in (video, sound):
            for packet in stream.encode():
                out.mux(packet)


# ---- one measured run, in a fresh process -------------------------------------------------
def _peak_rss_mib() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _spatial_fill(frames, masks, channel_axis=None):
    import clpde

    return np.stack(
        [
            clpde.inpaint(f, m, channel_axis=channel_axis) if m.any() else f
            for f, m in zip(frames, masks, strict=True)
        ]
    )


def child(args) -> None:
    from clpde.film.restore import restore_film
    from clpde.film.stream import WindowWork

    work = WindowWork(fill=_spatial_fill) if args.work == "spatial" else None
    mask = args.masks if args.work == "spatial" else None
    record = {"mode": args.mode}
    if args.mode == "one":
        from film_speed import Demand

        start, cpu, own = time.perf_counter(), time.process_time(), time.thread_time()
        with Demand() as demand:
            result = restore_film(
                args.film, args.out, mask=mask, work=work, block=args.block, progress=False
            )
        record["seconds"] = time.perf_counter() - start
        record["cpu_seconds"] = time.process_time() - cpu  # every thread of the process
        # what a shared machine does not change (film_speed.py): the calling thread's own
        # CPU (reading, writing and the serial steps) and the cores busy if given 2
        record["serial_cpu_seconds"] = time.thread_time() - own
        record["cores_if_given_2"] = demand.cores_if_given(2)
        record["load_average"] = os.getloadavg()[0]
    else:
        from clpde.scale.cluster import connect

        with connect(workers=args.workers, threads=1) as (client, info):
            record["cluster_seconds"] = info["seconds"]
            start, cpu = time.perf_counter(), time.process_time()
            before = client.run(time.process_time)
            result = restore_film(
                args.film,
                args.out,
                mask=mask,
                work=work,
                block=args.block,
                client=client,
                chunk_frames=args.chunk_frames,
                progress=False,
            )
            record["seconds"] = time.perf_counter() - start
            after = client.run(time.process_time)
            record["worker_cpu_seconds"] = sorted(after[w] - before[w] for w in after)
            record["cpu_seconds"] = time.process_time() - cpu + sum(record["worker_cpu_seconds"])
            record["worker_peak_mib"] = sorted(client.run(_peak_rss_mib).values())
    record.update(
        frames=result.frames,
        fps=result.frames / record["seconds"],
        peak_mib=_peak_rss_mib(),
        masked_pixels=result.masked_pixels,
        frames_sha256=result.frames_sha256,
    )
    print("RESULT " + json.dumps(record))


def measure(film: Path, masks: Path, out: Path, mode: str, args) -> dict:
    command = [
        sys.executable,
        __file__,
        "--child",
        "--mode",
        mode,
        "--film",
        str(film),
        "--out",
        str(out),
        "--masks",
        str(masks),
        "--work",
        args.work,
        "--block",
        str(args.block),
        "--chunk-frames",
        str(args.chunk_frames),
        "--workers",
        str(args.workers),
    ]
    done = subprocess.run(
        command,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    for line in done.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    raise RuntimeError(f"{mode} run failed:\n{done.stderr[-3000:]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--lengths",
        default="150,300",
        help="film lengths in frames, comma-separated (default 150,300)",
    )
    parser.add_argument("--full", action="store_true", help="also run the 3000-frame film")
    parser.add_argument("--work", choices=("film", "spatial"), default="film")
    parser.add_argument("--block", type=int, default=16)
    parser.add_argument("--chunk-frames", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--modes", default="one,dask")
    parser.add_argument(
        "--size",
        default="720x576",
        help="frame size WxH (default PAL 720x576; smaller to show memory flat "
        "in length on long runs quickly)",
    )
    parser.add_argument("--source", choices=("pan", "corpus"), default="pan")
    parser.add_argument(
        "--clip-frames", type=int, default=24, help="frames of each corpus clip (--source corpus)"
    )
    parser.add_argument("--json", default=str(RESULTS))
    # the measured run itself
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--mode", help=argparse.SUPPRESS)
    parser.add_argument("--film", help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    parser.add_argument("--masks", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return
    global WIDTH, HEIGHT
    WIDTH, HEIGHT = (int(x) for x in args.size.lower().split("x"))
    lengths = [int(x) for x in args.lengths.split(",")] + ([3000] if args.full else [])
    rows = []
    with tempfile.TemporaryDirectory(prefix="film_long.") as tmp:
        tmp = Path(tmp)
        for length in lengths:
            film, masks = tmp / f"pal_{length}.mp4", tmp / f"masks_{length}"
            masks.mkdir()
            start = time.perf_counter()
            make_film(
                film,
                length,
                masks if args.work == "spatial" else None,
                args.source,
                args.clip_frames,
            )
            made = time.perf_counter() - start
            for mode in args.modes.split(","):
                out = tmp / f"out_{length}_{mode}.mp4"
                row = {
                    "length": length,
                    "size": args.size,
                    "source": args.source,
                    "make_seconds": made,
                    **measure(film, masks, out, mode, args),
                }
                out.unlink()
                rows.append(row)
                workers = row.get("worker_peak_mib")
                given = row.get("cores_if_given_2")
                print(
                    f"{length:5d} frames {mode:4s}: {row['fps']:6.3f} frames/s, "
                    f"{row['seconds']:8.1f} s, CPU {row['cpu_seconds']:8.1f} s, "
                    f"peak {row['peak_mib']:7.0f} MiB"
                    + (
                        f", serial CPU {row['serial_cpu_seconds']:.1f} s, {given:.2f} cores "
                        f"busy if given 2 (so {given * length / row['cpu_seconds']:.3f} "
                        f"frames/s, estimated), load average {row['load_average']:.1f}"
                        if given
                        else ""
                    )
                    + (
                        f", workers {', '.join(f'{w:.0f}' for w in workers)} MiB" if workers else ""
                    ),
                    flush=True,
                )
                # after every row: a run stopped early keeps what it measured
                Path(args.json).parent.mkdir(parents=True, exist_ok=True)
                Path(args.json).write_text(
                    json.dumps({"rows": rows, "args": vars(args)}, indent=1) + "\n"
                )
            film.unlink()
    summary = {}
    for mode in args.modes.split(","):
        mine = [r for r in rows if r["mode"] == mode]
        best = mine[-1]
        summary[mode] = {
            "fps_longest": best["fps"],
            "peak_mib_by_length": {r["length"]: r["peak_mib"] for r in mine},
            "worker_peak_mib_by_length": {r["length"]: r.get("worker_peak_mib") for r in mine},
            "seconds_3000": (best["seconds"] if best["length"] == 3000 else 3000 / best["fps"]),
            "seconds_3000_extrapolated": best["length"] != 3000,
        }
    if "one" in summary and "dask" in summary:
        for length in lengths:
            pair = {r["mode"]: r for r in rows if r["length"] == length}
            if {"one", "dask"} <= set(pair):
                summary.setdefault("speedup_by_length", {})[length] = (
                    pair["dask"]["fps"] / pair["one"]["fps"]
                )
                summary.setdefault("bitwise_equal_by_length", {})[length] = (
                    pair["dask"]["frames_sha256"] == pair["one"]["frames_sha256"]
                )
    print(json.dumps(summary, indent=1))
    for mode, s in summary.items():
        if isinstance(s, dict) and "seconds_3000" in s:
            how = (
                "extrapolated from the longest run"
                if s["seconds_3000_extrapolated"]
                else "measured"
            )
            print(f"{mode}: 3000 frames (2 min PAL) in {s['seconds_3000'] / 60:.1f} min ({how})")
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(
        json.dumps({"rows": rows, "summary": summary, "args": vars(args)}, indent=1) + "\n"
    )


if __name__ == "__main__":
    main()
