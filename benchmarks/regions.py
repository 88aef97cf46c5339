"""Region tracking (thesis section 2.2): time per step with its reinitialisations, against a
dense copy of the grid and against a baseline checkout of clpde, and the accuracy tables,
in one run.

1. Step time: a sphere of radius 0.35 carrying a cap on an N^3 grid (N = 64, 128, 256), by
   two flows: mean curvature flow (the speed recomputed from Phi every stage; on fine grids
   the surface moves a few thousandths of a cell per step) and a constant inward speed at
   the CFL limit (0.4 cells per step: the reinitialisation's worst case). `RegionTracker.
   advance` runs 32 steps, reinitialisations included (the one `advance` ends with too);
   the time per step is the total over 32, the fastest of 3 such runs (the constant flow
   turning back each run), after a warm-up advance that compiles every kernel. The
   yardstick is one device copy of the tracker's whole padded volume (every level set).
   With --baseline DIR the same measurement runs in a subprocess on the clpde sources in
   DIR (`git archive <commit> | tar -x -C DIR`), alternating with this tree's (A B A B), so
   the ratios come from one run under the same load; the load average is printed with each
   row.
2. Cap accuracy (this tree): a sphere of radius 0.9 with the cap z > 0.45 (angular radius
   60 degrees, 1/4 of the area) expanding at unit speed 0.5 for t = 0.5, at several
   spacings: relative error of the cap's area fraction at the end, with triangles split
   along Phi-hat = 0 (sub-triangle boundary) and with whole triangles labelled by their
   centre (zero order, as in the thesis' figures), the angular radius error and the
   sphere's area error.
3. Curvature-flow accuracy (this tree and the baseline): the tests' sphere of radius 0.9 at
   h = 0.1 (40^3) under mean curvature flow to t = 0.05 and Gaussian-curvature flow to t = 0.1:
   error of the area against the analytic radius, and of the cap's share.

   With --storages lists bricks (the default) this tree's two storages (RegionTracker's
   storage=) alternate the same way, and each row also gives a step alone, a
   reinitialisation with its band upkeep alone, and the level sets' device memory.

    python benchmarks/regions.py [--sizes 64 128 256] [--baseline DIR] [--repeats 2]
                                 [--storages lists bricks]
                                 [--spacings 0.1 0.07 0.05 0.035 0.025] [--json PATH]
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STEPS = 32
ROUNDS = 3  # timed runs per tracker: the fastest is the one least disturbed by other load
FLOWS = ("curvature", "constant")


def step_timing(n, flow, storage=None, radius=0.35, steps=STEPS, rounds=ROUNDS):
    """ms per step (reinitialisations included) of a cap on a sphere on an n^3 grid, the
    fastest of `rounds` runs of `steps` steps (the constant flow turns back each round, so
    the sphere keeps its size); then, apart, the fastest of 3 runs of 8 steps without a
    reinitialisation (ms per step) and of 3 reinitialisations with their band upkeep (ms
    each). Only the API that older checkouts share (RegionTracker, advance, step,
    stable_dt, reinitialize, scale), and storage= when given."""
    import pyopencl as cl
    import pyopencl.array as cla

    from clpde.regions.api import region_tracker as RegionTracker

    h = 1.0 / n
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij", sparse=True)
    phi = (np.sqrt(x**2 + y**2 + z**2) - radius).astype(np.float32)
    cap = np.broadcast_to((0.5 * radius - z).astype(np.float32), phi.shape)
    kw = {} if storage is None else {"storage": storage}
    if flow == "curvature":
        tracker = RegionTracker(phi, cap[None], h, speed="mean-curvature", scale=1.0 / h**2, **kw)
    else:  # inward at 1 cell per unit time: the CFL step moves the surface 0.4 cells
        tracker = RegionTracker(phi, cap[None], h, speed="constant", scale=1.0, **kw)
    q = tracker.runtime.queue
    calls = []
    plain = tracker.reinitialize

    def counted(*args, **kwargs):
        calls.append(1)
        return plain(*args, **kwargs)

    tracker.reinitialize = counted
    dt = tracker.stable_dt()
    tracker.advance(tracker.time + 4 * dt)  # warm-up: compiles every kernel
    q.finish()
    if hasattr(tracker, "band_sizes"):
        band, reinit_band = tracker.band_sizes()
    else:
        band, reinit_band = tracker.step_band.n, tracker.reinit_band.n
    # the four work buffers of every level set (cur, nxt, ls0, stage), at this band
    level_set_mib = 4 * tracker.cur.nbytes / 2**20
    bricks = getattr(tracker, "bricks", None)
    stored = None if bricks is None else int(bricks.stored_cells)
    times, reinits = [], []
    for k in range(rounds):
        if flow == "constant" and k:
            tracker.scale = -tracker.scale  # out again, or in again
        calls.clear()
        dt = tracker.stable_dt()
        start_steps = tracker.steps
        start = time.perf_counter()
        tracker.advance(tracker.time + steps * dt * (1 - 1e-9))
        q.finish()
        times.append((time.perf_counter() - start) / (tracker.steps - start_steps))
        reinits.append(len(calls))
    done = tracker.steps - start_steps
    step_only, reinit_only = [], []
    for _ in range(3):
        dt = tracker.stable_dt()
        q.finish()
        t0 = time.perf_counter()
        for _ in range(8):
            tracker.step(dt)
        q.finish()
        step_only.append((time.perf_counter() - t0) / 8)
        t0 = time.perf_counter()
        tracker.reinitialize()
        q.finish()
        reinit_only.append(time.perf_counter() - t0)
        if flow == "constant":
            tracker.scale = -tracker.scale
    # the yardstick: one device copy of a dense padded volume of every level set
    g = tracker.grid
    dense = [cla.empty(q, tracker.nc * g.volume, g.dtype) for _ in range(2)]
    copies = []
    for _ in range(5):
        q.finish()
        t0 = time.perf_counter()
        cl.enqueue_copy(q, dense[1].data, dense[0].data)
        q.finish()
        copies.append(time.perf_counter() - t0)
    return {
        "grid": n,
        "flow": flow,
        "storage": storage or "lists",
        "band_cells": int(band),
        "reinit_cells": int(reinit_band),
        "steps": int(done),
        "reinits": int(max(reinits)),
        "ms_per_step": 1e3 * min(times),
        "ms_per_step_rounds": [1e3 * t for t in times],
        "ms_step_only": 1e3 * min(step_only),
        "ms_reinit": 1e3 * min(reinit_only),
        "level_set_mib": level_set_mib,
        "stored_cells": stored,
        "cpu_s": time.process_time(),
        "copy_ms": 1e3 * float(np.median(copies)),
        "load": os.getloadavg()[0],
    }


def curvature_accuracy(storage=None):
    """Area and cap-share errors of the tests' curvature flows (h = 0.1)."""
    from clpde.regions.api import track_region

    h = 0.1
    ax = np.arange(40) * h - 39 * h / 2
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.9
    rows = []
    for beta, t, radius in (
        ("mean-curvature", 0.05, np.sqrt(0.81 - 4 * 0.05)),
        ("gaussian", 0.1, np.cbrt(0.729 - 3 * 0.1)),
    ):
        kw = {} if storage is None else {"storage": storage}
        end = track_region(
            phi,
            0.45 - z,
            beta=beta,
            t=t,
            spacing=h,
            saves=1,
            origin=(ax[0],) * 3,
            progress=False,
            **kw,
        )[-1]
        rows.append(
            {
                "flow": beta,
                "area_error": end.area() / (4 * np.pi * radius**2) - 1,
                "cap_share_error": end.area_fraction(0) / 0.25 - 1,
                "steps": end.step,
            }
        )
    return rows


def cap_accuracy(h, device=None, storage="lists"):
    from scipy.ndimage import map_coordinates

    from clpde.regions.api import track_region
    from clpde.regions.mesh import split_regions, surface_mesh

    margin = 10 * h
    ax = np.arange(-1.15 - margin, 1.15 + margin + 0.5 * h, h)
    z, y, x = ax[:, None, None], ax[None, :, None], ax[None, None, :]
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.9
    cap = np.ascontiguousarray(np.broadcast_to(0.45 - z, phi.shape))
    start = time.perf_counter()
    frames = track_region(
        phi,
        cap,
        beta=0.5,
        t=0.5,
        spacing=h,
        saves=1,
        origin=(ax[0],) * 3,
        keep_volumes=True,
        device=device,
        progress=False,
        storage=storage,
    )
    seconds = time.perf_counter() - start
    end = frames[-1]
    p = end.boundaries[0]
    angle = float(np.mean(np.arccos(np.clip(p[:, 2] / np.linalg.norm(p, axis=1), -1, 1))))
    # zero order: whole triangles labelled by the sign of Phi-hat at their centre
    mesh = surface_mesh(end.phi, h, (ax[0],) * 3)
    idx = ((np.asarray(mesh.vertices) - ax[0]) / h)[:, ::-1].T
    vals = map_coordinates(end.phihat[0], idx, order=1, mode="nearest")
    centre = vals[mesh.faces].mean(axis=1)
    zero_order = float(mesh.area_faces[centre < 0].sum() / mesh.area)
    _, _, labels, _ = split_regions(mesh.vertices, vals[:, None], mesh.faces)
    return {
        "spacing": h,
        "cells": int(phi.size),
        "seconds": seconds,
        "area_fraction_error": end.area_fraction(0) / 0.25 - 1,
        "zero_order_error": zero_order / 0.25 - 1,
        "angular_radius_error": angle / (np.pi / 3) - 1,
        "sphere_area_error": end.area() / (4 * np.pi * 1.15**2) - 1,
        "split_faces": int(len(labels) - len(mesh.faces)),
    }


def _in_checkout(source, task, *args):
    """Run `task` of this file in a subprocess on the clpde sources in `source` (its result
    as JSON on stdout's last line)."""
    env = dict(os.environ, PYTHONPATH=os.path.abspath(source))
    out = subprocess.run(
        [sys.executable, os.path.abspath(__file__), "--task", task, *map(str, args)],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _task(name, args):
    if name == "step":
        return step_timing(int(args[0]), args[1], *args[2:3])
    return curvature_accuracy(*args[:1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 256])
    parser.add_argument("--flows", nargs="+", default=list(FLOWS), choices=FLOWS)
    parser.add_argument(
        "--spacings", type=float, nargs="*", default=[0.1, 0.07, 0.05, 0.035, 0.025]
    )
    parser.add_argument(
        "--baseline",
        default=None,
        help="a folder holding an older checkout of clpde, timed alongside",
    )
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument(
        "--storages",
        nargs="+",
        default=["lists", "bricks"],
        choices=["lists", "bricks"],
        help="this tree's storages, timed in alternation (A B A B)",
    )
    parser.add_argument("--json", default=os.path.join("benchmarks", "results", "regions.json"))
    parser.add_argument("--task", nargs="+", help=argparse.SUPPRESS)  # the subprocess's work
    args = parser.parse_args()
    if args.task:
        print(json.dumps(_task(args.task[0], args.task[1:])))
        return
    from clpde.runtime import get_runtime

    rt = get_runtime()
    print(
        f"device: {rt.device.name.strip()} ({rt.device.platform.name.strip()}), "
        f"{rt.device.max_compute_units} compute units"
    )
    # (name, source, storage): this tree's storages, then the baseline (lists only)
    runs = [(s, ROOT, s) for s in args.storages]
    if args.baseline:
        runs.append(("baseline", args.baseline, None))
    timings = []
    print(
        f"{'grid':>5} {'flow':>9} {'tree':>8} {'band':>8} {'reinit band':>11} "
        f"{'reinits':>7} {'ms/step':>8} {'step ms':>8} {'reinit ms':>9} {'MiB':>6} "
        f"{'copy ms':>8} {'step/copy':>9} {'cpu s':>6} {'load':>5}"
    )
    for n in args.sizes:
        for flow in args.flows:
            for _ in range(args.repeats):
                for name, source, storage in runs:  # A B A B
                    extra = () if storage is None else (storage,)
                    row = _in_checkout(source, "step", n, flow, *extra)
                    row["tree"] = name
                    timings.append(row)
                    print(
                        f"{n:>5} {flow:>9} {name:>8} {row['band_cells']:>8} "
                        f"{row['reinit_cells']:>11} {row['reinits']:>3}/{row['steps']:<3} "
                        f"{row['ms_per_step']:>8.1f} {row.get('ms_step_only', 0):>8.1f} "
                        f"{row.get('ms_reinit', 0):>9.1f} {row.get('level_set_mib', 0):>6.0f} "
                        f"{row['copy_ms']:>8.1f} "
                        f"{row['ms_per_step'] / row['copy_ms']:>9.2f} "
                        f"{row.get('cpu_s', 0):>6.1f} {row['load']:>5.1f}",
                        flush=True,
                    )
            if len(runs) > 1:
                k = len(runs)
                block = timings[-k * args.repeats :]
                first = [r["ms_per_step"] for r in block[0::k]]
                for j in range(1, k):
                    other = [r["ms_per_step"] for r in block[j::k]]
                    ratios = [b / a for a, b in zip(first, other, strict=True)]
                    print(
                        f"{'':>5} {flow:>9} {runs[j][0]} / {runs[0][0]} (ms per step, "
                        "pairwise): " + ", ".join(f"{r:.2f}x" for r in ratios),
                        flush=True,
                    )
    curvature = {
        name: _in_checkout(source, "curvature", *extra)
        for name, source, extra in [(s, ROOT, (s,)) for s in args.storages]
        + ([("baseline", args.baseline, ())] if args.baseline else [])
    }
    print(f"\n{'flow':>15} {'tree':>8} {'steps':>5} {'area':>8} {'cap share':>9}")
    for name, rows in curvature.items():
        for row in rows:
            print(
                f"{row['flow']:>15} {name:>8} {row['steps']:>5} "
                f"{100 * row['area_error']:>7.2f}% {100 * row['cap_share_error']:>8.2f}%"
            )
    accuracy = []
    if args.spacings:
        print(
            f"\n{'h':>6} {'storage':>7} {'cells':>8} {'s':>6} {'cap area':>9} "
            f"{'zero order':>10} {'angle':>8} {'sphere':>8}"
        )
    for h in args.spacings:
        for storage in args.storages:
            row = cap_accuracy(h, storage=storage)
            row["storage"] = storage
            accuracy.append(row)
            print(
                f"{h:>6} {storage:>7} {row['cells']:>8} {row['seconds']:>6.1f} "
                f"{100 * row['area_fraction_error']:>8.3f}% "
                f"{100 * row['zero_order_error']:>9.3f}% "
                f"{100 * row['angular_radius_error']:>7.3f}% "
                f"{100 * row['sphere_area_error']:>7.3f}%",
                flush=True,
            )
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, "w") as f:
        json.dump(
            {
                "device": rt.device.name.strip(),
                "step_timing": timings,
                "curvature_accuracy": curvature,
                "cap_accuracy": accuracy,
            },
            f,
            indent=1,
        )
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
