"""Region tracking (thesis section 2.2): per-step time against band size, and the tracked
cap's area error against grid spacing, in one run.

1. Step time: a sphere carrying a cap on an N^3 grid (N = 128, 256; two radii each) moving
   by mean curvature flow (the speed is recomputed from Phi every step). A step is one Heun
   step of Phi and the Phi-hat over the band (4 launches); a reinitialisation (every 4
   steps: 10 extension steps of the Phi-hat and 6 Heun iterations of both over the band
   dilated by 3 cells, then the bands' rebuild) is timed apart, the rebuild also alone.
   Times are means over repeated calls after a warm-up (the first launch compiles).
2. Cap accuracy: a sphere of radius 0.9 with the cap z > 0.45 (angular radius 60 degrees,
   1/4 of the area) expanding at unit speed 0.5 for t = 0.5, at several spacings: relative
   error of the cap's area fraction at the end, with triangles split along Phi-hat = 0
   (sub-triangle boundary) and with whole triangles labelled by their centre (zero order,
   as in the thesis' figures), and the angular radius error.

    python benchmarks/regions.py [--sizes 128 256] [--spacings 0.1 0.07 0.05 0.035 0.025]
                                 [--json PATH]
"""

import argparse
import json
import os
import time

import numpy as np

from clpde.regions import RegionTracker, surface_mesh, track_region
from clpde.regions_mesh import split_regions
from clpde.runtime import get_runtime


def step_timing(n, radius_fraction, steps=10, device=None):
    h = 1.0 / n
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij", sparse=True)
    r = radius_fraction
    phi = (np.sqrt(x**2 + y**2 + z**2) - r).astype(np.float32)
    cap = np.broadcast_to((0.5 * r - z).astype(np.float32), phi.shape)
    tracker = RegionTracker(phi, cap[None], h, speed="mean-curvature", scale=1.0 / h**2,
                            device=device)
    q = tracker.runtime.queue
    dt = tracker.stable_dt()
    tracker.step(dt)  # warm-up
    q.finish()
    start = time.perf_counter()
    for _ in range(steps):
        tracker.step(dt)
    q.finish()
    per_step = (time.perf_counter() - start) / steps
    reinit = _mean_seconds(tracker.reinitialize, q)
    rebuild = _mean_seconds(tracker.rebuild, q)
    return {"grid": n, "radius": r, "band_cells": tracker.step_band.n,
            "reinit_cells": tracker.reinit_band.n, "step_ms": 1e3 * per_step,
            "ns_per_band_cell": 1e9 * per_step / tracker.step_band.n,
            "reinit_ms": 1e3 * reinit, "rebuild_ms": 1e3 * rebuild}


def _mean_seconds(call, queue, repeats=3):
    call()  # warm-up
    queue.finish()
    start = time.perf_counter()
    for _ in range(repeats):
        call()
    queue.finish()
    return (time.perf_counter() - start) / repeats


def cap_accuracy(h, device=None):
    margin = 10 * h
    ax = np.arange(-1.15 - margin, 1.15 + margin + 0.5 * h, h)
    z, y, x = ax[:, None, None], ax[None, :, None], ax[None, None, :]
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.9
    cap = np.ascontiguousarray(np.broadcast_to(0.45 - z, phi.shape))
    start = time.perf_counter()
    frames = track_region(phi, cap, beta=0.5, t=0.5, spacing=h, saves=1,
                          origin=(ax[0],) * 3, keep_volumes=True, device=device)
    seconds = time.perf_counter() - start
    end = frames[-1]
    p = end.boundaries[0]
    angle = float(np.mean(np.arccos(np.clip(p[:, 2] / np.linalg.norm(p, axis=1), -1, 1))))
    # zero order: whole triangles labelled by the sign of Phi-hat at their centre
    mesh = surface_mesh(end.phi, h, (ax[0],) * 3)
    from scipy.ndimage import map_coordinates

    idx = ((np.asarray(mesh.vertices) - ax[0]) / h)[:, ::-1].T
    vals = map_coordinates(end.phihat[0], idx, order=1, mode="nearest")
    centre = vals[mesh.faces].mean(axis=1)
    zero_order = float(mesh.area_faces[centre < 0].sum() / mesh.area)
    _, _, labels, _ = split_regions(mesh.vertices, vals[:, None], mesh.faces)
    return {"spacing": h, "cells": int(phi.size), "seconds": seconds,
            "area_fraction_error": end.area_fraction(0) / 0.25 - 1,
            "zero_order_error": zero_order / 0.25 - 1,
            "angular_radius_error": angle / (np.pi / 3) - 1,
            "sphere_area_error": end.area() / (4 * np.pi * 1.15**2) - 1,
            "split_faces": int(len(labels) - len(mesh.faces))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[128, 256])
    parser.add_argument("--spacings", type=float, nargs="+",
                        default=[0.1, 0.07, 0.05, 0.035, 0.025])
    parser.add_argument("--device", default=None)
    parser.add_argument("--json", default=os.path.join("benchmarks", "results", "regions.json"))
    args = parser.parse_args()
    rt = get_runtime(args.device)
    print(f"device: {rt.device.name.strip()} ({rt.device.platform.name.strip()})")
    timings = []
    print(f"{'grid':>5} {'radius':>6} {'band':>9} {'reinit band':>11} {'step ms':>8} "
          f"{'ns/cell':>8} {'reinit ms':>9} {'rebuild ms':>10}")
    for n in args.sizes:
        for r in (0.2, 0.35):
            row = step_timing(n, r, device=args.device)
            timings.append(row)
            print(f"{n:>5} {r:>6} {row['band_cells']:>9} {row['reinit_cells']:>11} "
                  f"{row['step_ms']:>8.1f} {row['ns_per_band_cell']:>8.1f} "
                  f"{row['reinit_ms']:>9.1f} "
                  f"{row['rebuild_ms']:>10.1f}")
    accuracy = []
    print(f"\n{'h':>6} {'cells':>8} {'s':>6} {'cap area':>9} {'zero order':>10} {'angle':>8} "
          f"{'sphere':>8}")
    for h in args.spacings:
        row = cap_accuracy(h, args.device)
        accuracy.append(row)
        print(f"{h:>6} {row['cells']:>8} {row['seconds']:>6.1f} "
              f"{100 * row['area_fraction_error']:>8.3f}% {100 * row['zero_order_error']:>9.3f}% "
              f"{100 * row['angular_radius_error']:>7.3f}% {100 * row['sphere_area_error']:>7.3f}%")
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, "w") as f:
        json.dump({"device": rt.device.name.strip(), "step_timing": timings,
                   "cap_accuracy": accuracy}, f, indent=1)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
