"""Effective memory bandwidth of clpde's planar and ROF kernels, against the copy roofline.

For each size (1024^2, 2048^2, 4096^2 float32 by default), on one device:

- the copy roofline: a copy kernel over the same ghost-padded layout (fields.cl
  copy_interior, 8 bytes per cell) and cl.enqueue_copy of the whole buffer; the larger of
  the two effective bandwidths is the roofline (the table says which);
- every kernel's time per launch and its effective bandwidth: the bytes it must read and
  write once per step (e.g. 8 bytes per cell for heat in float32: read u, write v) divided by
  that time; its ratio to the roofline. The planar steps write their own ghost layer
  (MIRROR_GHOSTS in kernels/common/common.h), so one launch is a whole step; the time of a
  separate ghost refill (Field.fill_ghosts, two thin launches) is shown for reference;
- the same step in NumPy, timed with the numpy references of the same schemes
  (tests/reference/), and the speedup per step.

And end to end: clpde.diffuse(image, flow="heat", steps=500) on a 2048^2 float32 image
(upload, 500 steps, download), counted as 8 * N * 500 bytes.

Times are the best of several repeats of back-to-back launches. Prints a table; writes JSON.

    python benchmarks/bandwidth.py [--device cpu] [--sizes 1024 2048 4096] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

# (E402: these import the repository's clpde and tests, so they follow the sys.path line)
import clpde  # noqa: E402
from clpde.fields import Field, Grid  # noqa: E402
from tests.reference import planar as ref_planar  # noqa: E402
from tests.reference import rof as ref_rof  # noqa: E402


def device_time(queue, launch, min_seconds=0.1, repeats=9):
    """Best time per launch over `repeats` batches of back-to-back launches."""
    launch()
    queue.finish()
    start = time.perf_counter()
    launch()
    queue.finish()
    one = max(time.perf_counter() - start, 1e-6)
    batch = int(min(200, max(2, min_seconds / one)))
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(batch):
            launch()
        queue.finish()
        best = min(best, (time.perf_counter() - start) / batch)
    return best


def host_time(fn, budget=3.0):
    """Best time of a NumPy call; fewer repeats for slow ones."""
    start = time.perf_counter()
    fn()
    first = time.perf_counter() - start
    best = first
    for _ in range(int(min(4, budget / max(first, 1e-6)))):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


class Case:
    """One kernel: how to launch it on the device and the NumPy reference of its step."""

    def __init__(self, name, bytes_per_cell, launch, numpy_step):
        self.name, self.bytes_per_cell = name, bytes_per_cell
        self.launch, self.numpy_step = launch, numpy_step


def cases(grid: Grid, rng):
    rt, q, n = grid.runtime, grid.runtime.queue, grid.nx
    host = rng.random((1, n, n)).astype(np.float32)
    u = Field.from_host(grid, host)
    v = Field.from_host(grid, host)
    u0 = Field.from_host(grid, host + 0.01 * rng.standard_normal(host.shape).astype(np.float32))
    weight = Field.from_host(grid, rng.random((1, n, n)).astype(np.float32))
    lam = cla.to_device(q, np.array([8.0], np.float32))
    k = grid.kernel
    f32 = np.float32
    pad = ref_planar.pad_neumann(host)
    pad0 = ref_planar.pad_neumann(u0.to_host())
    padw = weight.to_host()[0]
    ub, vb, u0b = u.data.data, v.data.data, u0.data.data

    heat = k("planar/planar.cl", "planar_heat_step")
    pm_exp = k("planar/planar.cl", "planar_perona_malik_step", EDGE_STOP=0)
    pm_rat = k("planar/planar.cl", "planar_perona_malik_step", EDGE_STOP=1)
    tv = k("planar/planar.cl", "planar_tv_step")
    curv = k("planar/planar.cl", "planar_curvature_step")
    curv_w = k("planar/planar.cl", "planar_curvature_step", HAS_WEIGHT=1)
    rof = k("planar/planar.cl", "planar_rof_step")
    lam_rows = k("planar/planar.cl", "planar_rof_lambda_rows")
    partial = cla.empty(q, 4 * grid.ny, np.float32)

    dual = [
        cla.to_device(q, (0.3 * rng.standard_normal((1, grid.plane, 2))).astype(f32))
        for _ in range(3)
    ]
    dual_step = k("planar/rof.cl", "rof_dual_step")
    dual_rows = k("planar/rof.cl", "rof_dual_rows")
    dual_host = [d.get().reshape(1, grid.ny + 2, grid.sx, 2) for d in dual]

    def rows(kernel, *args):  # one work-item per row, as clpde launches the row sums
        local = (1, 1, 1) if rt.is_cpu else None
        return lambda: kernel(q, (1, grid.ny, 1), local, *args, *grid.args(grid.nx))

    return [
        Case(
            "planar_heat_step",
            8,
            lambda: grid.launch(heat, ub, vb, f32(0.2)),
            lambda: ref_planar.heat_step(pad, 0.2),
        ),
        Case(
            "perona_malik_step exp",
            8,
            lambda: grid.launch(pm_exp, ub, vb, f32(0.2), f32(1 / 0.05**2)),
            lambda: ref_planar.perona_malik_step(pad, 0.2, 0.05, "exp"),
        ),
        Case(
            "perona_malik_step rational",
            8,
            lambda: grid.launch(pm_rat, ub, vb, f32(0.2), f32(1 / 0.05**2)),
            lambda: ref_planar.perona_malik_step(pad, 0.2, 0.05, "rational"),
        ),
        Case(
            "planar_tv_step",
            8,
            lambda: grid.launch(tv, ub, vb, f32(0.01), f32(0.05**2)),
            lambda: ref_planar.tv_step(pad, 0.01, 0.05),
        ),
        Case(
            "planar_curvature_step",
            8,
            lambda: grid.launch(curv, ub, vb, ub, f32(0.2), f32(1e-10)),
            lambda: ref_planar.curvature_step(pad, 0.2, 1e-10),
        ),
        Case(
            "curvature_step weighted",
            12,
            lambda: grid.launch(curv_w, ub, vb, weight.data.data, f32(0.2), f32(1e-10)),
            lambda: ref_planar.curvature_step(pad, 0.2, 1e-10, padw),
        ),
        Case(
            "planar_rof_step",
            12,
            lambda: grid.launch(rof, ub, vb, u0b, lam.data, f32(0.004), f32(0.02**2)),
            lambda: ref_planar.rof_step(pad, pad0, [8.0], 0.004, 0.02),
        ),
        Case(
            "planar_rof_lambda_rows",
            8,
            rows(lam_rows, ub, u0b, partial.data, f32(0.02**2)),
            lambda: ref_planar.rof_lambda(pad, pad0, 0.02, 0.01),
        ),
        Case(
            "rof_dual_step",
            28,
            lambda: grid.launch(
                dual_step, dual[0].data, dual[1].data, dual[2].data, u0b, lam.data, f32(0.5)
            ),
            lambda: ref_rof.dual_step(dual_host[0], dual_host[1], pad0, [8.0], 0.5),
        ),
        Case(
            "rof_dual_rows",
            20,
            rows(dual_rows, dual[0].data, u0b, lam.data, vb, partial.data),
            lambda: ref_rof.dual_rows(dual_host[0], pad0, [8.0], host),
        ),
    ]


def measure_size(runtime, n, rng, numpy_budget):
    q = runtime.queue
    grid = Grid(runtime, n, n, 1, 1, np.dtype(np.float32))
    cells = n * n
    a = Field.from_host(grid, rng.random((1, n, n)).astype(np.float32))
    b = Field.empty(grid)
    copy_k = grid.kernel("common/fields.cl", "fields_copy_interior")
    t_kernel = device_time(q, lambda: grid.launch(copy_k, a.data.data, b.data.data))
    t_enqueue = device_time(q, lambda: cl.enqueue_copy(q, b.data.data, a.data.data))
    copy_kernel_bw = 8 * cells / t_kernel
    enqueue_bw = 2 * a.data.nbytes / t_enqueue
    roof = max(copy_kernel_bw, enqueue_bw)
    which = "copy kernel" if copy_kernel_bw >= enqueue_bw else "enqueue_copy"
    ghost_t = device_time(q, lambda: b.fill_ghosts())
    out = {
        "n": n,
        "copy_kernel_GBps": copy_kernel_bw / 1e9,
        "enqueue_copy_GBps": enqueue_bw / 1e9,
        "roofline_GBps": roof / 1e9,
        "roofline_from": which,
        "fill_ghosts_ms": ghost_t * 1e3,
        "kernels": [],
    }
    for case in cases(grid, rng):
        t = device_time(q, case.launch)
        t_np = host_time(case.numpy_step, numpy_budget)
        bw = case.bytes_per_cell * cells / t
        out["kernels"].append(
            {
                "kernel": case.name,
                "bytes_per_cell": case.bytes_per_cell,
                "ms": t * 1e3,
                "GBps": bw / 1e9,
                "fraction_of_copy": bw / roof,
                "numpy_ms": t_np * 1e3,
                "speedup_vs_numpy": t_np / t,
            }
        )
    return out


def end_to_end(runtime, n=2048, steps=500, repeats=3):
    image = np.random.default_rng(1).random((n, n)).astype(np.float32)
    clpde.diffuse(image[:64, :64], flow="heat", steps=2, device=runtime)  # build
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        clpde.diffuse(image, flow="heat", steps=steps, device=runtime, progress=False)
        best = min(best, time.perf_counter() - start)
    return {"n": n, "steps": steps, "seconds": best, "GBps": 8 * n * n * steps / best / 1e9}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="clpde device (default cpu)")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096])
    parser.add_argument(
        "--numpy-budget",
        type=float,
        default=2.0,
        help="seconds per NumPy timing (fewer repeats for slow steps)",
    )
    parser.add_argument(
        "--json", default=os.path.join(ROOT, "benchmarks", "results", "bandwidth.json")
    )
    args = parser.parse_args(argv)
    runtime = clpde.get_runtime(args.device)
    rng = np.random.default_rng(0)
    print(
        f"device: {runtime.device.name.strip()} ({runtime.platform.name.strip()}), "
        f"{runtime.device.max_compute_units} compute units; load average "
        f"{os.getloadavg()[0]:.1f} (other processes slow PoCL's threads)",
        flush=True,
    )

    sizes = []
    for n in args.sizes:
        res = measure_size(runtime, n, rng, args.numpy_budget)
        sizes.append(res)
        print(
            f"\n{n} x {n} float32: copy kernel {res['copy_kernel_GBps']:.1f} GB/s, "
            f"enqueue_copy {res['enqueue_copy_GBps']:.1f} GB/s -> roofline "
            f"{res['roofline_GBps']:.1f} GB/s ({res['roofline_from']}); "
            f"fill_ghosts {res['fill_ghosts_ms']:.3f} ms"
        )
        header = (
            f"  {'kernel':28s} {'B/cell':>6s} {'ms':>8s} {'GB/s':>6s} {'of copy':>7s} "
            f"{'numpy ms':>9s} {'x numpy':>8s}"
        )
        print(header)
        for k in res["kernels"]:
            print(
                f"  {k['kernel']:28s} {k['bytes_per_cell']:6d} {k['ms']:8.3f} "
                f"{k['GBps']:6.1f} {k['fraction_of_copy']:7.0%} "
                f"{k['numpy_ms']:9.1f} {k['speedup_vs_numpy']:7.1f}x",
                flush=True,
            )

    e2e = end_to_end(runtime)
    roof2048 = next((s["roofline_GBps"] for s in sizes if s["n"] == 2048), None)
    e2e["fraction_of_copy"] = e2e["GBps"] / roof2048 if roof2048 else None
    frac = f" = {e2e['fraction_of_copy']:.0%} of copy" if roof2048 else ""
    print(
        f"\nend to end: diffuse(2048^2 float32, heat, 500 steps) {e2e['seconds']:.3f} s, "
        f"{e2e['GBps']:.1f} GB/s{frac}"
    )
    print(
        "(B/cell: bytes each step must read and write once; of copy: effective bandwidth / "
        "roofline; x numpy: numpy reference time / kernel time)"
    )

    result = {
        "device": runtime.device.name.strip(),
        "platform": runtime.platform.name.strip(),
        "compute_units": runtime.device.max_compute_units,
        "host": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "load_average_1_5_15": list(os.getloadavg()),
        "sizes": sizes,
        "end_to_end_heat": e2e,
    }
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with tempfile.NamedTemporaryFile(
        "w", dir=os.path.dirname(os.path.abspath(args.json)), delete=False, suffix=".tmp"
    ) as tmp:
        json.dump(result, tmp, indent=2)
    os.replace(tmp.name, args.json)
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
