"""Reliability figures: thread races, memory over many calls, and the cost of a small call.

    python benchmarks/reliability.py [--device cpu] [--calls 1000] [--json PATH]
    python benchmarks/reliability.py overhead [--calls 2000]   # only the small-call loop

- **threads**: 4 threads calling `diffuse(img, "heat", steps=100)` on 8 different 128x128
  images, 5 rounds, against the same calls made one after another: how many of the 40
  results differ bitwise (before clpde locked each launch: 1 to 5 of 24 per round);
- **memory**: `calls` calls in a loop of each of diffuse (64x64, 10 steps), denoise_tv
  (64x64, 20 iterations), inpaint (48x48, a 10x16 hole) and PlanarFlow made, run and
  dropped; the process's resident memory (on a CPU device the buffers are host memory,
  so this counts the device's too) and the number of live pyopencl memory objects,
  sampled every tenth of the loop after 20 warm-up calls; flat means the last sample
  is within a few MiB of the first and no memory object is left;
- **overhead**: the median wall time of one `diffuse` call on 64x64 for 10 steps. For a
  before/after comparison run the `overhead` mode as a whole process against each tree.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np


def _rss_mib() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _live_memory_objects() -> int:
    import pyopencl as cl

    gc.collect()
    return sum(isinstance(o, cl.MemoryObject) for o in gc.get_objects())


def threads(device, rounds=5) -> dict:
    import clpde

    rng = np.random.default_rng(0)
    images = [rng.random((128, 128)).astype(np.float32) for _ in range(8)]

    def call(image):
        return clpde.diffuse(image, "heat", steps=100, device=device)

    serial = [call(im) for im in images]
    differ = 0
    for _ in range(rounds):
        with ThreadPoolExecutor(4) as pool:
            threaded = list(pool.map(call, images))
        differ += sum(not np.array_equal(a, b) for a, b in zip(serial, threaded, strict=False))
    return {"results": rounds * len(images), "differ": differ}


def memory(device, calls: int) -> dict:
    import clpde

    rng = np.random.default_rng(1)
    small = rng.random((64, 64)).astype(np.float32)
    hole_image = rng.random((48, 48)).astype(np.float32)
    mask = np.zeros(hole_image.shape, bool)
    mask[16:26, 16:32] = True
    work = {
        "diffuse": lambda: clpde.diffuse(small, "heat", steps=10, device=device),
        "denoise_tv": lambda: clpde.denoise_tv(small, 0.1, max_steps=20, device=device),
        "inpaint": lambda: clpde.inpaint(
            hole_image, mask, max_steps=20, fill="mean", device=device
        ),
        "PlanarFlow": lambda: clpde.PlanarFlow(small, "tv", device=device).run(10).result(),
    }
    out = {}
    for name, fn in work.items():
        for _ in range(20):
            fn()
        samples = []
        start = time.perf_counter()
        for i in range(calls + 1):
            if i % max(1, calls // 10) == 0:
                samples.append((i, round(_rss_mib(), 2), _live_memory_objects()))
            if i < calls:
                fn()
        seconds = time.perf_counter() - start
        out[name] = {
            "samples": samples,
            "rss_growth_mib": round(samples[-1][1] - samples[0][1], 2),
            "memory_objects_left": samples[-1][2],
            "ms_per_call": round(1e3 * seconds / calls, 3),
        }
    return out


def overhead(device, calls: int) -> dict:
    import clpde

    image = np.random.default_rng(2).random((64, 64)).astype(np.float32)
    for _ in range(20):
        clpde.diffuse(image, "heat", steps=10, device=device)
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        clpde.diffuse(image, "heat", steps=10, device=device)
        times.append(time.perf_counter() - t0)
    return {
        "calls": calls,
        "median_ms": round(1e3 * statistics.median(times), 4),
        "min_ms": round(1e3 * min(times), 4),
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mode", nargs="?", default="all", choices=["all", "overhead"])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--calls", type=int, default=None)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    import clpde

    runtime = clpde.get_runtime(args.device)
    if args.mode == "overhead":
        result = overhead(args.device, args.calls or 2000)
        print(
            f"diffuse 64x64, 10 steps: median {result['median_ms']} ms per call "
            f"(min {result['min_ms']}) over {result['calls']} calls  [{clpde.__file__}]"
        )
        return
    calls = args.calls or 1000
    report = {
        "device": repr(runtime),
        "load_average": os.getloadavg(),
        "threads": threads(args.device),
        "memory": memory(args.device, calls),
        "overhead": overhead(args.device, 2000),
    }
    t = report["threads"]
    print(f"device: {report['device']}; load average {report['load_average']}")
    print(f"threads: {t['differ']} of {t['results']} threaded heat results differ from serial")
    print(
        f"memory over {calls} calls: {'call':<12} {'RSS growth':>11} {'objects left':>13} "
        f"{'ms/call':>8}"
    )
    for name, m in report["memory"].items():
        print(
            f"{'':>24}{name:<12} {m['rss_growth_mib']:>8.2f} MiB {m['memory_objects_left']:>13} "
            f"{m['ms_per_call']:>8.3f}"
        )
    o = report["overhead"]
    print(f"overhead: diffuse 64x64, 10 steps: median {o['median_ms']} ms per call")
    path = (
        Path(args.json) if args.json else (Path(__file__).parent / "results" / "reliability.json")
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
