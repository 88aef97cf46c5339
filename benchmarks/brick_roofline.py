"""What bounds a heat step plus its re-extension on the band, lists against bricks.

    python benchmarks/brick_roofline.py [--n 217] [--steps 10] [--reps 5] [--json PATH]

One unit sphere on an n^3 grid (spacing 2 / (n - 17), as benchmarks/surface_accuracy.py
section 6), float32, every kernel timed interleaved with the others (best of --reps runs of
--steps launches), against a device copy of the whole padded grid (the yardstick of the
target: a step plus its re-extension in at most one such copy):

- the steps: the lists' heat_step over the node runs, the bricks' brick_heat_step (8x8x8),
  and heat_step over every cell of whole rows of the box (the dense stencil: its arithmetic
  ceiling with long vector loops);
- the re-extensions of the reach band: the lists' extend_cp, the bricks' brick_extend_cp;
- their bandwidth ceilings, the same cells with the same access and no arithmetic: the
  lists' band_copy (v = u + psi over the runs) and the bricks' brick_copy (over every cell
  of the bricks holding a node);
- the bytes and flops each must move and do per cell, the arithmetic intensity, and the
  time the copy's bandwidth would allow for those bytes.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

# The benchmarks' own kernels: no part of the library, built by their path.
ROOFLINE_CL = str(Path(__file__).resolve().parent / "kernels" / "roofline.cl")


# flops a cell of the heat step does (surface/heat.cl's heat_div, unweighted): four fluxes,
# each 3 one-sided differences, psi's central normal (3 differences, 3 products), |N|^2 (5),
# the projection (5 for the dot, 1 division, 6 for v - s N), then the divergence (6) and the
# update (2): 4 * 26 + 8
STEP_FLOPS = 4 * 26 + 8
# the tricubic re-extension: the y-z weights (2 x 10 for the polynomials), 16 rows of 4 nodes
# weighed and summed (4 x (4 x 8) as 4-vectors: 128), the x weights and the dot (10 + 7)
EXT_FLOPS = 20 + 128 + 17
EXT_LOADS = 16  # 4-wide vector loads of the stencil's rows, per re-extended cell


def measure(n: int, steps: int, reps: int) -> dict:
    import pyopencl as cl
    import pyopencl.array as cla

    import clpde
    from clpde.surface import ImplicitSurface
    from clpde.surface.storage import BandFlow, BrickFlow, _offsets, _signs

    rt = clpde.get_runtime()
    surf = ImplicitSurface.sphere(1.0, 2.0 / (n - 17))
    g, q = surf.grid, rt.queue
    u = surf.field(lambda x, y, z: x * y, dtype=np.float32)
    r = g.scalar(0.1)
    flow = BandFlow(surf, u)
    k_list = g.kernel("surface/heat.cl", "heat_step", WEIGHTED=0)
    k_band_copy = g.kernel(ROOFLINE_CL, "band_copy")
    runs = surf.step_runs
    surf.storage, surf.band.brick = "bricks", (8, 8, 8)
    bf = BrickFlow(surf, u)
    k_brick = bf.kernel("surface/bricks.cl", "bricks_heat_step", WEIGHTED=0)
    k_brick_copy = bf.kernel(ROOFLINE_CL, "brick_copy")
    b_u = cla.zeros(q, (bf.bricks.nbricks + 2) * bf.bricks.cells_per_brick, np.float32)
    b_v = cla.zeros_like(b_u)
    b_p = cla.zeros_like(b_u)

    from surface_accuracy import _dense_runs

    dense = _dense_runs(g, q)
    dense_cells = int((dense.end.get() - dense.start.get()).sum())
    big = cla.zeros(q, g.volume, np.float32)
    big2 = cla.zeros_like(big)
    kernels = {
        "dense step": lambda: g.launch_runs(
            k_list, dense, big.data, big2.data, surf.psi_dev.data, r, *_offsets(g, 0), *g.strides()
        ),
        "list step": lambda: g.launch_runs(
            k_list,
            runs,
            flow.cur.data,
            flow.tmp.data,
            surf.psi_dev.data,
            r,
            *_offsets(g, 0),
            *g.strides(),
        ),
        "list re-extension": flow.after_step,
        "list band_copy": lambda: g.launch_runs(
            k_band_copy, runs, flow.cur.data, flow.tmp.data, surf.psi_dev.data
        ),
        "brick step": lambda: bf.bricks.launch(
            k_brick, bf.cur.data, bf.tmp.data, bf.psi.data, r, *_signs(0), bf.bricks.node_rows.data
        ),
        "brick re-extension": bf.after_step,
        "brick_copy": lambda: bf.bricks.launch(k_brick_copy, b_u.data, b_v.data, b_p.data),
    }
    a = cla.empty(q, g.volume, np.float32)
    a.fill(1.0)
    b = cla.empty_like(a)
    kernels["dense copy"] = lambda: cl.enqueue_copy(q, b.data, a.data)

    def timed(fn):
        q.finish()
        start = time.perf_counter()
        for _ in range(steps):
            fn()
        q.finish()
        return (time.perf_counter() - start) / steps

    for fn in kernels.values():
        fn()
    best = {name: np.inf for name in kernels}
    for _ in range(reps):
        for name, fn in kernels.items():
            best[name] = min(best[name], timed(fn))
    t_copy = best["dense copy"]
    copy_gbs = 2 * a.nbytes / t_copy / 1e9
    run_cells = int((runs.end.get()[: runs.n] - runs.start.get()[: runs.n]).sum())
    brick_cells = int(np.count_nonzero(bf.bricks.brick_bits.get()[1 : bf.bricks.nbricks + 1] & 1))
    brick_cells *= bf.bricks.cells_per_brick
    visited = int(bf.bricks.node_rows.get().astype(np.int64).sum()) * 8
    reach = surf.reach_band.n
    # bytes each must move at least: the step reads u and psi and writes v per cell it
    # updates; the re-extension reads target, first node, 3 offsets and writes 1 (24 B)
    cells = {
        "dense step": dense_cells,
        "list step": run_cells,
        "list band_copy": run_cells,
        "brick step": visited,
        "brick_copy": brick_cells,
        "list re-extension": reach,
        "brick re-extension": reach,
    }
    per_cell_bytes = {
        "dense step": 12,
        "list step": 12,
        "list band_copy": 12,
        "brick step": 12,
        "brick_copy": 12,
        "list re-extension": 24,
        "brick re-extension": 24,
    }
    flops = {
        "dense step": STEP_FLOPS,
        "list step": STEP_FLOPS,
        "brick step": STEP_FLOPS,
        "list re-extension": EXT_FLOPS,
        "brick re-extension": EXT_FLOPS,
        "list band_copy": 1,
        "brick_copy": 1,
    }
    rows = []
    for name in cells:
        t = best[name]
        nbytes = cells[name] * per_cell_bytes[name]
        rows.append(
            {
                "kernel": name,
                "ms": 1e3 * t,
                "x_copy": t / t_copy,
                "cells": cells[name],
                "ns_per_cell": 1e9 * t / cells[name],
                "bytes_per_cell": per_cell_bytes[name],
                "flops_per_cell": flops[name],
                "intensity": flops[name] / per_cell_bytes[name],
                "gbs": nbytes / t / 1e9,
                "gflops": cells[name] * flops[name] / t / 1e9,
                "bandwidth_floor_ms": 1e3 * nbytes / (copy_gbs * 1e9),
            }
        )
    out = {
        "grid": n,
        "padded_cells": g.volume,
        "ext_band": surf.ext_band.n,
        "node_band": surf.node_band.n,
        "reach_band": reach,
        "run_cells": run_cells,
        "brick_cells_with_nodes": brick_cells,
        "brick_rows_visited_cells": visited,
        "nbricks": bf.bricks.nbricks,
        "stored_cells": bf.bricks.stored_cells,
        "copy_ms": 1e3 * t_copy,
        "copy_gbs": copy_gbs,
        "rows": rows,
    }
    print(
        f"{n}^3: padded {g.volume} cells, extension band {surf.ext_band.n}, nodes "
        f"{surf.node_band.n}, reach {reach}; dense copy {1e3 * t_copy:.2f} ms "
        f"({copy_gbs:.1f} GB/s)"
    )
    print(
        f"{'kernel':>20} {'ms':>7} {'x copy':>7} {'cells':>9} {'ns/cell':>8} {'B/cell':>6} "
        f"{'flop/cell':>9} {'GB/s':>6} {'GFLOP/s':>8} {'floor ms':>8}"
    )
    for row in rows:
        print(
            f"{row['kernel']:>20} {row['ms']:7.2f} {row['x_copy']:7.2f} {row['cells']:9d} "
            f"{row['ns_per_cell']:8.2f} {row['bytes_per_cell']:6d} {row['flops_per_cell']:9d} "
            f"{row['gbs']:6.2f} {row['gflops']:8.2f} {row['bandwidth_floor_ms']:8.2f}"
        )
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=217)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    out = measure(args.n, args.steps, args.reps)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
