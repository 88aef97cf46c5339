"""Every surface flow in both band storages, in one run: time per step, memory, agreement.

    python benchmarks/surface_flows_storage.py [--sizes 64 128 217 256] [--steps 20]
        [--repeats 3] [--flows heat tv denoise harmonic along turk] [--json out.json]

The unit sphere on an n^3 grid (spacing 2 / (n - 17)), float32, data in the band form
(values at the extension band's cells). For each flow and storage: the time of one step
with its re-extension (and TV's lambda updates), the flow's step loop timed on its own
(the progress_range of flows.py and textures.py wrapped: the queue finished before the
first step and after the last; set-up, uploads and the read-back excluded) over --steps
steps, lists and bricks alternated (A B A B) --repeats times, the ratio bricks / lists
taken pairwise; the device memory of the flow's state (its buffers, not the surface's shared
psi and lists); the largest difference between the two storages' results over the largest value;
and the yardsticks: a device copy of one padded float32 volume of the grid (best of 5), the step in
those copies, and in ns per cell of the extension band.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def flows_for(surf):
    """name -> (channels, call(u, steps)) for each flow, steps of its stable default dt."""

    x, y, z = surf.coordinates()
    direction = np.stack(np.broadcast_arrays(-y, x, 0 * z))  # along the parallels
    h2 = surf.spacing**2
    dt_heat, dt_tv = h2 / 6, h2 / 6 / 1.0
    return {
        "heat": (1, lambda u, k: surf.heat(u, k * dt_heat, dt=dt_heat)),
        "tv": (1, lambda u, k: surf.tv(u, k * dt_tv, dt=dt_tv)),
        # the dynamic lambda updated every 10 steps, its sums in the step's time
        "denoise": (1, lambda u, k: surf.denoise_tv(u, sigma=0.05, t=k * dt_tv / 2, dt=dt_tv / 2)),
        "harmonic": (3, lambda u, k: surf.harmonic_map(u, k * dt_tv, p=1, dt=dt_tv)),
        "along": (1, lambda u, k: surf.diffuse_along(u, direction, k * dt_heat, dt=dt_heat)),
        "turk": (2, lambda u, k: surf.reaction_diffusion(k, state=u, dt=0.15)),
    }


def band_data(surf, channels):
    if channels == 1:
        return surf.band_field(lambda x, y, z: x * y + np.sin(3 * z))
    if channels == 2:
        return np.stack(
            [
                surf.band_field(lambda x, y, z: 4 + 0.1 * x),
                surf.band_field(lambda x, y, z: 4 + 0.1 * y),
            ]
        )
    v = np.stack(
        [
            surf.band_field(lambda x, y, z: x + 0.2),
            surf.band_field(lambda x, y, z: y),
            surf.band_field(lambda x, y, z: z),
        ]
    )
    return v / np.sqrt((v**2).sum(axis=0))


def state_bytes(surf, storage, channels):
    """Device bytes of a flow's state (cur, tmp; the bricks' psi tiles too)."""
    from clpde.surface import storage as band_storage

    surf.storage = storage
    u = band_data(surf, channels)
    f = band_storage.make_flow(surf, u)
    total = f.cur.nbytes + f.tmp.nbytes
    if storage == "bricks":
        total += f.psi.nbytes
    return total


LOOPS: list[float] = []


def timed_range(progress, n, *args, **kwargs):
    """flows.progress_range that records the seconds per step of its loop in LOOPS."""
    import clpde

    queue = clpde.get_runtime().queue
    queue.finish()
    start = time.perf_counter()
    yield from range(n)
    queue.finish()
    LOOPS.append((time.perf_counter() - start) / max(n, 1))


def time_flow(call, u, steps):
    LOOPS.clear()
    out = call(u, steps)
    out = out[0] if isinstance(out, tuple) else out
    return 1e3 * LOOPS[-1], out


def dense_copy_ms(surf) -> float:
    """Best of 5 device copies of one padded float32 volume of the grid."""
    import pyopencl as cl
    import pyopencl.array as cla

    q = surf.runtime.queue
    a = cla.zeros(q, surf.grid.padded_shape, np.float32)
    b = cla.empty_like(a)
    best = np.inf
    for _ in range(6):
        q.finish()
        start = time.perf_counter()
        cl.enqueue_copy(q, b.data, a.data)
        q.finish()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


def run_size(n, names, steps, repeats):
    from clpde.surface import ImplicitSurface

    start = time.perf_counter()
    surf = ImplicitSurface.sphere(1.0, 2.0 / (n - 17))
    build = time.perf_counter() - start
    copy_ms = dense_copy_ms(surf)
    print(
        f"{n:>4}^3: extension band {surf.ext_band.n} cells, a dense copy {copy_ms:.2f} ms",
        flush=True,
    )
    table = flows_for(surf)
    rows = []
    for name in names:
        channels, call = table[name]
        u = band_data(surf, channels)
        results, times = {}, {"lists": [], "bricks": []}
        for storage in ("lists", "bricks"):  # warm-up: builds, the bricks' set-up
            surf.storage = storage
            call(u, 2)
        for _ in range(repeats):
            for storage in ("lists", "bricks"):
                surf.storage = storage
                ms, results[storage] = time_flow(call, u, steps)
                times[storage].append(ms)
        ratios = [b / a for a, b in zip(times["lists"], times["bricks"], strict=True)]
        diff = float(
            np.abs(results["bricks"] - results["lists"]).max()
            / max(1e-30, np.abs(results["lists"]).max())
        )
        mem = {s: state_bytes(surf, s, channels) / 2**20 for s in ("lists", "bricks")}
        rows.append(
            {
                "n": n,
                "flow": name,
                "channels": channels,
                "ms_lists": times["lists"],
                "ms_bricks": times["bricks"],
                "ratio": ratios,
                "rel_diff": diff,
                "mib_lists": mem["lists"],
                "mib_bricks": mem["bricks"],
                "band": surf.ext_band.n,
                "build_s": build,
                "copy_ms": copy_ms,
            }
        )
        best = {k: min(times[k]) for k in times}
        print(
            f"{n:>4}^3 {name:>9} ({channels} ch): lists "
            f"{' '.join(f'{t:7.1f}' for t in times['lists'])} ms, bricks "
            f"{' '.join(f'{t:7.1f}' for t in times['bricks'])} ms, bricks/lists "
            f"{' '.join(f'{r:.2f}' for r in ratios)}; state {mem['lists']:.0f} / "
            f"{mem['bricks']:.0f} MiB; results differ by {diff:.1e}; best step "
            f"{best['lists'] / copy_ms:.1f} / {best['bricks'] / copy_ms:.1f} dense copies, "
            f"{1e6 * best['lists'] / surf.ext_band.n:.1f} / "
            f"{1e6 * best['bricks'] / surf.ext_band.n:.1f} ns per band cell",
            flush=True,
        )
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 217, 256])
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--flows", nargs="+", default=["heat", "tv", "denoise", "harmonic", "along", "turk"]
    )
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    import clpde
    from clpde.surface import flows, textures

    flows.progress_range = textures.progress_range = timed_range
    rt = clpde.get_runtime()
    print(f"device: {rt.device.name.strip()}")
    rows = [row for n in args.sizes for row in run_size(n, args.flows, args.steps, args.repeats)]
    if args.json:
        args.json.write_text(json.dumps({"device": rt.device.name.strip(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
