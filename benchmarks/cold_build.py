"""Cold build of a first run: the OpenCL programs it builds and the time it takes, each run
in a fresh process with an empty PoCL kernel cache.

A run imports clpde, then times its first calls: the program builds (Runtime._build, timed
by wrapping it) and the whole first calls, in wall and in CPU seconds (CPU time is the
steadier figure on a shared machine; PoCL compiles in the calling process). Cases:

- `planar` (the default): clpde.diffuse (heat, 2 steps) and clpde.denoise_tv (sigma 0.1) on
  a 64 x 64 float32 image;
- `inpaint`: clpde.inpaint's default on a colour photo (chelsea's top left 150 x 225),
  then on a grey one (camera's 256 x 256), each with text and four 12 px blobs; repeat
  calls of both are timed at the end, new sizes are crops of 0.4, 0.45 and 0.35 of the
  photos' sides;
- `surface`: a unit sphere at spacing 0.1, its heat flow (t = 0.01) and a TV denoising with
  the dynamic lambda (sigma 0.3, t = 0.01).

The import is counted in the first calls' wall time. After the first calls the same calls
run again on three other sizes (images of 61, 80 and
97 pixels a side; spheres at spacing 0.09, 0.11 and 0.12), in the same process: *new sizes*
is their mean wall time, each followed by the same size again (the ratio of the two sums is
printed), the cost of meeting an input size for the first time once the
programs are built (PoCL builds a kernel again for each new work-group size; see
tests/core/test_work_groups.py).

With --other PATH the same runs are made with PYTHONPATH=PATH as well, alternating with this
checkout's, so that both meet the same load: `--other /path/to/main` compares a branch with
main.

    python benchmarks/cold_build.py [--case planar|surface|inpaint] [--runs 5] [--device cpu]
                                    [--other PATH] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

ONE_RUN = r"""
import json, sys, time
wall_import = time.perf_counter()
import numpy as np
import clpde
wall_import = time.perf_counter() - wall_import
from clpde import runtime

built = []
build = runtime.Runtime._build
def timed(self, filename, dtype, defines):
    start = time.perf_counter()
    program = build(self, filename, dtype, defines)
    built.append([filename, np.dtype(dtype).name, dict(defines), time.perf_counter() - start])
    return program
runtime.Runtime._build = timed
def inpaint_calls(size):
    # a colour photo, then a grey one, each with text and blobs, at `size` (a scale)
    from skimage import data as skd
    from clpde.data import damage_mask
    from scipy import ndimage
    out = []
    for photo in (skd.chelsea(), skd.camera()):
        ny, nx = int(photo.shape[0] * size), int(photo.shape[1] * size)  # a crop
        image = np.ascontiguousarray(photo[:ny, :nx])
        mask = damage_mask((ny, nx), seed=3, text=True, scratches=False)
        yy, xx = np.mgrid[0:ny, 0:nx]
        for k in range(4):
            mask |= np.hypot(yy - ny * (0.2 + 0.2 * k), xx - nx * (0.8 - 0.15 * k)) < 6
        start, cpu = time.perf_counter(), time.process_time()
        clpde.inpaint(image, mask, channel_axis=-1 if image.ndim == 3 else None,
                      progress=False, device=sys.argv[1])
        out.append(time.perf_counter() - start)
        cpu_calls.append(time.process_time() - cpu)
    return out
cpu_calls = []
def calls(size):
    if sys.argv[2] == "inpaint":
        return inpaint_calls(size)
    if sys.argv[2] == "planar":
        image = np.random.default_rng(0).random((size, size)).astype(np.float32)
        clpde.diffuse(image, "heat", steps=2, device=sys.argv[1])
        clpde.denoise_tv(image, sigma=0.1, device=sys.argv[1])
    else:
        from clpde.surface import ImplicitSurface
        surf = ImplicitSurface.sphere(1.0, spacing=size, device=sys.argv[1])
        u = np.random.default_rng(0).normal(size=surf.shape)
        surf.heat(u, 0.01)
        surf.denoise_tv(u, sigma=0.3, t=0.01)
first, later = {"planar": (64, (61, 80, 97)), "surface": (0.1, (0.09, 0.11, 0.12)),
                "inpaint": (0.5, (0.4, 0.45, 0.35))}[sys.argv[2]]
wall, cpu = time.perf_counter(), time.process_time()
parts = calls(first)
wall, cpu = wall_import + time.perf_counter() - wall, time.process_time() - cpu
n_first = len(built)
new, again = [], []
for size in later:  # a size met for the first time, then the same size again
    start = time.perf_counter()
    calls(size)
    new.append(time.perf_counter() - start)
    start = time.perf_counter()
    calls(size)
    again.append(time.perf_counter() - start)
result = {"programs": built, "wall": wall, "cpu": cpu, "new_sizes": sum(new) / len(new),
          "new_size_ratio": sum(new) / sum(again), "import": wall_import,
          "new_size_programs": built[n_first:]}
if sys.argv[2] == "inpaint":
    start = time.perf_counter()
    n = len(cpu_calls)
    repeat = calls(first)
    result.update(first_calls=parts, repeat_calls=repeat, repeat=time.perf_counter() - start,
                  first_cpu=cpu_calls[:2], repeat_cpu=cpu_calls[n:])
print(json.dumps(result))
"""


def one_run(pythonpath: Path, device: str, case: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="clpde-cold-") as cache:
        env = dict(os.environ, POCL_CACHE_DIR=cache, PYTHONPATH=str(pythonpath))
        out = subprocess.run(
            [sys.executable, "-c", ONE_RUN, device, case],
            env=env,
            cwd=cache,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--case", choices=("planar", "surface", "inpaint"), default="planar")
    parser.add_argument(
        "--other",
        type=Path,
        default=None,
        help="another checkout to time alternately (e.g. main's)",
    )
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    trees = {"this checkout": ROOT} | ({"other": args.other} if args.other else {})
    runs = {name: [] for name in trees}
    for _ in range(args.runs):
        for name, path in trees.items():
            runs[name].append(one_run(path, args.device, args.case))
    print(
        f"{'tree':14s} {'programs built':40s} {'build s':>8s} {'first calls s':>14s} "
        f"{'CPU s':>6s} {'new sizes s':>12s}   (medians of {args.runs} cold runs)"
    )
    summary = {}
    for name, results in runs.items():
        programs = ", ".join(p[0] for p in results[0]["programs"])
        build = statistics.median(sum(p[3] for p in r["programs"]) for r in results)
        wall = statistics.median(r["wall"] for r in results)
        cpu = statistics.median(r["cpu"] for r in results)
        new = statistics.median(r["new_sizes"] for r in results)
        summary[name] = {
            "path": str(trees[name]),
            "programs": programs,
            "build_s": build,
            "first_calls_s": wall,
            "cpu_s": cpu,
            "new_sizes_s": new,
            "runs": results,
        }
        print(f"{name:14s} {programs:40s} {build:8.3f} {wall:14.3f} {cpu:6.3f} {new:12.3f}")
        ratio = statistics.median(r["new_size_ratio"] for r in results)
        summary[name]["new_size_ratio"] = ratio
        print(
            f"    a new size over the same size again: {ratio:.2f}x; programs built for new "
            f"sizes: {len(results[0]['new_size_programs'])}; import "
            f"{statistics.median(r['import'] for r in results):.2f} s"
        )
        if args.case == "inpaint":
            first = [statistics.median(r["first_calls"][i] for r in results) for i in (0, 1)]
            rep = [statistics.median(r["repeat_calls"][i] for r in results) for i in (0, 1)]
            imp = statistics.median(r["import"] for r in results)
            extra = imp + sum(first) - sum(rep)
            summary[name].update(
                first_colour_s=first[0],
                first_grey_s=first[1],
                repeat_colour_s=rep[0],
                repeat_grey_s=rep[1],
                extra_s=extra,
            )
            fc = [statistics.median(r["first_cpu"][i] for r in results) for i in (0, 1)]
            rc = [statistics.median(r["repeat_cpu"][i] for r in results) for i in (0, 1)]
            summary[name].update(first_cpu_s=fc, repeat_cpu_s=rc, extra_cpu_s=sum(fc) - sum(rc))
            print(
                f"    CPU seconds: first colour {fc[0]:.2f} (repeat {rc[0]:.2f}), first grey "
                f"{fc[1]:.2f} (repeat {rc[1]:.2f}): first calls - repeats = "
                f"{sum(fc) - sum(rc):.2f} s of CPU"
            )
            print(
                f"    first colour {first[0]:.2f} s (repeat {rep[0]:.2f}), first grey "
                f"{first[1]:.2f} s (repeat {rep[1]:.2f}): import + first calls - repeats = "
                f"{extra:.2f} s; {len(results[0]['programs'])} programs"
            )
        for i, prog in enumerate(results[0]["programs"]):
            times = statistics.median(
                r["programs"][i][3] for r in results if len(r["programs"]) > i
            )
            print(f"    {prog[0]:22s} {prog[1]:8s} {times:6.3f} s  {prog[2]}")
    if args.json:
        args.json.write_text(json.dumps(summary, indent=1))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
