"""A big sphere on this machine: memory and time of a heat flow in band form.

    python benchmarks/surface_big.py [--n 512] [--steps 20] [--storage lists,bricks]

The unit sphere on an n^3 grid (spacing 2 / (n - 17): from_function pads its box by 8
cells a side), float32. Data in the band form (values at the extension band's cells only,
ImplicitSurface.band_field): no dense float64 copy of the data. Reported: the times of the
surface's construction and of each storage's set-up, the time per heat step with its
re-extension (a call of --steps steps less a call of one, over steps - 1; best of 2), the
error of u = xy against the exact exp(-6t) xy at 2000 points through surf.sample, and the
process's peak resident memory after each phase (ru_maxrss; PoCL's device buffers live in
it) and the device memory PoCL reports.
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np


def rss_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=512)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--storage", default="lists,bricks")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    import clpde
    from clpde.surface import ImplicitSurface
    from clpde.surface.exact import sphere_points, xy_exact

    rt = clpde.get_runtime()
    out = {
        "device": rt.device.name.strip(),
        "global_mem_gb": rt.global_mem / 2**30,
        "max_alloc_gb": rt.max_alloc / 2**30,
        "n": args.n,
    }
    start = time.perf_counter()
    surf = ImplicitSurface.sphere(1.0, 2.0 / (args.n - 17))
    out.update(
        shape=list(surf.shape),
        spacing=surf.spacing,
        ext_band=surf.ext_band.n,
        node_band=surf.node_band.n,
        reach_band=surf.reach_band.n,
        build_s=time.perf_counter() - start,
        rss_after_build_gb=rss_gb(),
    )
    print(
        f"grid {surf.shape}, spacing {surf.spacing:.5f}, extension band {surf.ext_band.n}, "
        f"built in {out['build_s']:.1f} s, peak RSS {out['rss_after_build_gb']:.2f} GB "
        f"(PoCL reports {out['global_mem_gb']:.1f} GB device memory, "
        f"{out['max_alloc_gb']:.1f} GB per buffer)"
    )
    u = surf.band_field(lambda x, y, z: x * y)
    dt = surf.stability_limit()
    pts = sphere_points(2000)
    t_total = args.steps * dt
    results = {}
    for storage in args.storage.split(","):
        surf.storage = storage
        start = time.perf_counter()
        surf.heat(u, dt)  # set-up (the bricks' build) and one step
        setup = time.perf_counter() - start
        one = many = np.inf
        for _ in range(2):  # a step's own time: (many steps - one step) / (steps - 1)
            start = time.perf_counter()
            surf.heat(u, dt, dt=dt)
            one = min(one, time.perf_counter() - start)
            start = time.perf_counter()
            v = surf.heat(u, t_total, dt=dt)
            many = min(many, time.perf_counter() - start)
        per_step = (many - one) / (args.steps - 1)
        err = float(np.abs(surf.sample(v, pts) - xy_exact(pts, t_total)).max())
        results[storage] = {
            "setup_s": setup,
            "one_step_s": one,
            "steps_s": many,
            "ms_per_step": 1e3 * per_step,
            "error": err,
            "rss_gb": rss_gb(),
        }
        print(
            f"{storage:>7}: first call (set-up) {setup:.1f} s, a call of 1 step {one:.2f} s "
            f"(upload, whole-band extensions, read-back), of {args.steps} steps {many:.2f} s: "
            f"{1e3 * per_step:.0f} ms a step; xy error at t = {t_total:.2e}: {err:.2e}; "
            f"peak RSS {rss_gb():.2f} GB"
        )
    out["storages"] = results
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
