"""Where a batch's CPU goes: per thread of every worker and of the client, per task.

    python benchmarks/batch_trace.py [--photos 40] [--workers 2] [--threads 1]

Inpaints --photos 512x512 photos (those of benchmarks/batch.py) with `clpde batch` twice:
on clpde's local cluster and on a plain Dask LocalCluster (Dask's worker settings, the
"before" of clpde.scale.cluster.WORKER_CONFIG and of the preload's malloc settings), and the serial
loop in this process. Every process first inpaints one photo untimed (its kernels). For
each, the CPU (user and system, from /proc) of each thread over the timed part, divided by
the number of photos of the whole batch (so the rows add up to the CPU per photo), and the
minor page faults per photo. Threads: "task" runs the inpaintings (a worker's Dask thread,
the serial loop's main thread), "event loop" Dask's communication and monitors (with the
scheduler, in the client), "main" the client's caller (hashes, manifest), "other" native
threads (PoCL's, which run the kernels).
CPU time hardly depends on what else the machine runs; compare rows of one run.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from batch import dask_cluster, make_photos, scratch_mask  # noqa: E402


def thread_cpu(main: str = "event loop") -> dict:
    """{thread kind: [user s, system s]} of this process, and its minor page faults; `main`:
    the kind of the main thread (a worker's runs its event loop)."""
    import resource
    import threading

    names = {t.native_id: t.name for t in threading.enumerate()}
    tick = os.sysconf("SC_CLK_TCK")
    kinds: dict = {}
    for tid in os.listdir("/proc/self/task"):
        with open(f"/proc/self/task/{tid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        name = names.get(int(tid))
        if name is None:
            kind = "other"
        elif "Dask-Default-Threads" in name:
            kind = "task"
        elif name == "MainThread":
            kind = main
        else:
            kind = "event loop"
        user, system = int(fields[11]) / tick, int(fields[12]) / tick
        totals = kinds.setdefault(kind, [0.0, 0.0])
        totals[0] += user
        totals[1] += system
    kinds["faults"] = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    return kinds


def warm(photo, mask):
    import clpde
    from clpde.io.images import read_image

    clpde.inpaint(read_image(photo), read_image(mask) > 0, channel_axis=-1, progress=False)


def difference(after: dict, before: dict) -> dict:
    out = {}
    for kind, value in after.items():
        if kind == "faults":
            out[kind] = value - before.get(kind, 0)
        else:
            base = before.get(kind, [0.0, 0.0])
            out[kind] = [value[0] - base[0], value[1] - base[1]]
    return out


def report(label: str, parts: list[tuple[str, dict]], count: int, wall: float) -> None:
    print(
        f"\n{label}: {count / wall:.2f} photos/s ({wall:.1f} s wall, load {os.getloadavg()[0]:.1f})"
    )
    total = 0.0
    for process, kinds in parts:
        for kind, value in sorted(kinds.items()):
            if kind == "faults":
                continue
            total += value[0] + value[1]
            print(
                f"  {process:10s} {kind:10s} user {1000 * value[0] / count:6.1f}  system "
                f"{1000 * value[1] / count:5.1f} ms/photo"
            )
        print(f"  {process:10s} {'faults':10s} {kinds['faults'] / count:8.0f} /photo")
    print(f"  total {1000 * total / count:.1f} ms of CPU per photo")


def run_batch(photos, mask, workers, threads, plain: bool) -> None:
    import importlib

    from distributed import Client

    batch = importlib.import_module("clpde.scale.batch")
    out = Path(tempfile.mkdtemp(prefix="clpde-trace-"))
    if plain:
        cluster = dask_cluster(workers, threads)
    else:
        cluster, workers, threads = importlib.import_module("clpde.scale.cluster").start_cluster(
            workers, threads
        )
    with Client(cluster, set_as_default=False) as client:
        client.wait_for_workers(workers, timeout=120)
        client.run(warm, str(photos[0]), str(mask))
        before, client_before = client.run(thread_cpu), thread_cpu("main")
        start = time.perf_counter()
        result = batch.batch(
            "inpaint", photos, out, mask=mask, client=client, force=True, progress=False
        )
        wall = time.perf_counter() - start
        after, client_after = client.run(thread_cpu), thread_cpu("main")
    cluster.close()
    assert result.ok, result.failed
    parts = [(f"worker {k}", difference(after[a], before[a])) for k, a in enumerate(after)]
    parts.append(("client", difference(client_after, client_before)))
    label = "plain Dask LocalCluster" if plain else "clpde's local cluster"
    report(f"{label}, {workers} x {threads}", parts, len(photos), wall)


def run_serial(photos, mask) -> None:
    import clpde
    from clpde.io.images import read_image, write_image

    out = Path(tempfile.mkdtemp(prefix="clpde-trace-"))
    m = read_image(mask) > 0
    warm(photos[0], mask)
    before, start = thread_cpu("task"), time.perf_counter()
    for p in photos:
        write_image(out / p.name, clpde.inpaint(read_image(p), m, channel_axis=-1, progress=False))
    wall = time.perf_counter() - start
    report(
        "serial loop (this process)",
        [("serial", difference(thread_cpu("task"), before))],
        len(photos),
        wall,
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=40)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--threads", type=int, default=1, help="PoCL threads per worker")
    args = parser.parse_args()
    from clpde.io.images import write_image

    work = Path(tempfile.mkdtemp(prefix="clpde-trace-"))
    (work / "photos").mkdir()
    photos = make_photos(work / "photos", args.photos)
    mask = work / "mask.png"
    write_image(mask, scratch_mask(512, 512).astype("uint8") * 255)
    print(
        f"{args.photos} photos of 512x512; POCL_MAX_PTHREAD_COUNT of the serial loop: "
        f"{os.environ.get('POCL_MAX_PTHREAD_COUNT', 'PoCL default')}"
    )
    run_batch(photos, mask, args.workers, args.threads, plain=False)
    run_batch(photos, mask, args.workers, args.threads, plain=True)
    run_serial(photos, mask)


if __name__ == "__main__":
    main()
