"""The 2D band of MorphingTracker in bricks against its cell lists, in one run.

    python benchmarks/track_bricks.py [--json PATH] [--rounds N] [--steps N] [--device D]

For each frame pair (the tracking benchmark's: a synthetic 64x64 sequence of
tests/tracking/test_track.py and an MNI152 axial slice pair, 233x197, when nilearn's data files
are installed; then synthetic 176x144 (carphone's size), 512^2, 1024^2 and 2048^2 frames
with a disc and a wavy blob) it times, per layout (lists, bricks 8x8, bricks 16x4):

- `step`: one morph_track launch over the band (the tracker's default features and
  discrepancy: grey intensity, NCC over a 7x7 window), and the same with the thesis'
  F2 - F1 (`step F2-F1`, less arithmetic per cell). Bricks sum each cell's window as the
  lists do; `--tiled` adds bricks that slide the sums over the brick (morph_track_tiled,
  what MorphingTracker(storage='bricks...') runs on CPUs);
- `reinit`: one reinitialisation iteration over the rebuild's region (the band dilated by
  REACH cells), the tracker's reinitialisation;
- `rebuild`: a whole rebuild (dilation, 5 reinitialisation iterations, band marking and
  compaction: the upkeep);

with the band's cells against the cells its launches visit (stored: lists visit the band's
cells, bricks every movable cell of the bricks holding one). Then whole tracks with the
default options (the synthetic sequence, 8 frames, and MNI152 z = 90..99), ms per frame.
Each round times every layout in turn (A B C A B C ...), `--steps` launches each after a
warm-up; the table gives the median over rounds of the wall time per launch and of the
process CPU time per launch, and the speed-ups over the lists of both (the CPU time is the
steadier on a shared machine).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "track_bricks.json"
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "tests" / "track")]
LAYOUTS = ("lists", "bricks8x8", "bricks16x4")
# With --groups, the GPU launch geometry (a work-group per brick) too, run on the CPU.
GROUPED = ("bricks8x8 wg", "bricks16x4 wg")
# With --tiled, bricks whose NCC step slides the window sums over the brick
# (morph_track_tiled); their other launches are the plain bricks'.
TILED = ("bricks8x8 tiled", "bricks16x4 tiled")


def blob_frames(ny, nx):
    """Two frames of a disc and a wavy blob (the second moved by (1.5, 2) pixels)."""
    y, x = np.mgrid[:ny, :nx] + 0.0
    s = min(ny, nx)

    def scene(dy, dx):
        disc = np.hypot(x - 0.35 * nx - dx, y - 0.4 * ny - dy) < 0.22 * s
        t = np.arctan2(y - 0.65 * ny - dy, x - 0.7 * nx - dx)
        r = 0.15 * s * (1 + 0.25 * np.cos(5 * t))
        blob = np.hypot(x - 0.7 * nx - dx, y - 0.65 * ny - dy) < r
        return disc | blob

    masks = [scene(0, 0), scene(1.5, 2.0)]
    return np.stack([0.2 + 0.6 * m for m in masks]).astype(np.float32), masks[0]


def cases():
    from test_track import synthetic_sequence

    frames, masks = synthetic_sequence("deform", frames=2)
    yield "synthetic deform 64x64", frames, masks[0]
    try:
        from tracking import mni_slices

        frames, masks = mni_slices(90, 2)
        yield f"MNI152 wm z=90 {frames.shape[2]}x{frames.shape[1]}", frames, masks[0]
    except SystemExit as exc:
        print(f"(skipped MNI152: {exc})")
    for ny, nx in ((144, 176), (512, 512), (1024, 1024), (2048, 2048)):
        yield f"blobs {nx}x{ny}", *blob_frames(ny, nx)


class Case:
    """One layout's level set, features and kernels on one frame pair."""

    def __init__(self, runtime, frames, mask, label):
        from clpde.tracking.levelset import LevelSet, signed_distance
        from clpde.tracking.morph import morph_kernel_name
        from clpde.tracking.options import DISCREPANCIES
        from clpde.tracking.preprocessing import feature_field
        from clpde.tracking.tracker import MorphingTracker

        layout, grouped, tiled = label.split()[0], label.endswith(" wg"), label.endswith("tiled")
        self.tracker = MorphingTracker(frames, mask, storage=layout, device=runtime)
        self.ls = ls = LevelSet(
            runtime,
            signed_distance(mask),
            self.tracker.options.band_width,
            np.float32,
            storage=layout,
            group_per_brick=grouped or None,
        )
        self.f1 = feature_field(self.tracker.prepared(0), ls, self.tracker.options)
        self.f2 = feature_field(self.tracker.prepared(1), ls, self.tracker.options)
        self.f1_out = self.f1.copy()
        # The tracker's kernels, but bricks without "tiled" sum the NCC's windows cell by
        # cell, as the lists do.
        self.morph = {}
        for disc in ("ncc", "difference"):
            name = morph_kernel_name(ls, disc)
            if name == "features_morph_track_tiled" and not tiled:
                name = "features_morph_track_bricks"
            self.morph[disc] = ls.band_kernel(
                "tracking/features.cl", name, NCH=1, DISC=DISCREPANCIES[disc], WIN=3
            )
        self.reinit = ls.band_kernel("tracking/levelset.cl", ls.store.KERNELS["reinit"])
        ls.dilate_band()
        self.near = ls.store.cells(ls._near_mask)
        self.stats = None
        import pyopencl.array as cla

        g = ls.grid
        self.stats = cla.zeros(runtime.queue, 5 * ls.band_parts() + 1, g.dtype)

    def step(self, disc):
        ls, g = self.ls, self.ls.grid
        ls.launch_band(
            self.morph[disc],
            ls.band,
            ls.u.cur.data.data,
            self.f1.data.data,
            self.f2.data.data,
            ls.band_mask.data,
            ls.u.cur.data.data,
            ls.u.nxt.data.data,
            self.f1_out.data.data,
            self.stats.data,
            g.scalar(0.5),
            g.scalar(0.02**2),
            g.scalar(1e-3**2),
            g.scalar(1.0),
            g.scalar(0.0),
            g.scalar(0.02),
            np.int32(g.sx),
            np.int32(g.plane),
        )

    def reinit_step(self):
        ls = self.ls
        args = (ls.u.cur.data.data, ls.u.cur.data.data, ls.u.nxt.data.data)
        ls.launch_band(self.reinit, self.near, *args, *ls.store.reinit_args(self.near, 0.5))

    def rebuild(self):
        self.ls.rebuild(5)

    def cells(self):
        ls = self.ls
        visited = ls.store.stored(self.near)
        return {
            "band": int(ls.band_cells().sum()),
            "band visited": ls.stored_cells(),
            "reinit region visited": int(visited),
        }


def timed(runtime, action, steps):
    """(wall s, CPU s) per call of action, after one warm-up call."""
    action()
    runtime.queue.finish()
    w, c = time.perf_counter(), time.process_time()
    for _ in range(steps):
        action()
    runtime.queue.finish()
    return (time.perf_counter() - w) / steps, (time.process_time() - c) / steps


def markdown(results) -> str:
    """The table of docs/tracking.md: CPU ms per launch, lists / 8x8 / 16x4 (then, for
    the NCC step, 8x8 and 16x4 tiled, when measured)."""
    lines = [
        "| frames | band cells | visited 8x8 / 16x4 | step (NCC) | step (F2-F1) | "
        "reinit iteration | rebuild |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, e in results["cases"].items():
        cells = e["lists"]["cells"]["band"]
        visited = " / ".join(str(e[lay]["cells"]["band visited"]) for lay in LAYOUTS[1:])
        cols = [
            " / ".join(
                f"{e[lay]['ms'][a][1]:.2f}"
                for lay in LAYOUTS + (tuple(t for t in TILED if t in e) if a == "step" else ())
            )
            for a in ("step", "step F2-F1", "reinit", "rebuild")
        ]
        lines.append(f"| {name} | {cells} | {visited} | " + " | ".join(cols) + " |")
    return "\n".join(lines)


def sequences():
    """Whole sequences for the end-to-end times: the tracking benchmark's."""
    from test_track import synthetic_sequence

    yield (
        "synthetic deform, 8 frames",
        synthetic_sequence("deform", frames=8)[0],
        synthetic_sequence("deform", frames=8)[1][0],
    )
    try:
        from tracking import mni_slices

        frames, masks = mni_slices(90, 10)
        yield "MNI152 wm z=90..99", frames, masks[0]
    except SystemExit:
        pass


def whole_tracks(rt, rounds, layouts):
    """ms per frame of clpde.track with the default options, each layout in turn."""
    from clpde.tracking.tracker import track

    out = {}
    for name, frames, first in sequences():
        times = {lay: [] for lay in layouts}
        for lay in layouts:  # warm-up: kernel builds
            track(frames[:2], first, storage=lay, device=rt)
        for _ in range(rounds):
            for lay in layouts:
                w, c = time.perf_counter(), time.process_time()
                track(frames, first, storage=lay, device=rt)
                n = len(frames) - 1
                times[lay].append(((time.perf_counter() - w) / n, (time.process_time() - c) / n))
        out[name] = {
            lay: [1e3 * statistics.median(t[k] for t in times[lay]) for k in (0, 1)]
            for lay in layouts
        }
        print(
            f"{name:34s} "
            + "  ".join(f"{lay} {m[0]:.1f}/{m[1]:.1f}" for lay, m in out[name].items())
            + "  ms/frame"
        )
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=RESULTS)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--device", default="cpu")
    parser.add_argument(
        "--groups",
        action="store_true",
        help="also the work-group-per-brick geometry (GPUs') on this device",
    )
    parser.add_argument(
        "--tiled", action="store_true", help="also bricks whose NCC step slides its window sums"
    )
    args = parser.parse_args(argv)
    layouts = LAYOUTS + (GROUPED if args.groups else ()) + (TILED if args.tiled else ())
    from clpde.runtime import get_runtime

    rt = get_runtime(args.device)
    print(
        f"device: {rt.device.name.strip()} ({rt.device.platform.version.strip()}), "
        f"{rt.device.max_compute_units} compute units"
    )
    actions = {
        "step": lambda c: c.step("ncc"),
        "step F2-F1": lambda c: c.step("difference"),
        "reinit": Case.reinit_step,
        "rebuild": Case.rebuild,
    }
    results = {"device": rt.device.name.strip(), "cases": {}}
    print(
        f"{'frames':26s} {'layout':13s} {'band':>7s} {'visited':>8s} "
        + " ".join(f"{a + ' ms':>15s}" for a in actions)
        + "   (wall / CPU)"
    )
    for name, frames, mask in cases():
        built = {lay: Case(rt, frames, mask, lay) for lay in layouts}
        times = {lay: {a: [] for a in actions} for lay in layouts}
        for _ in range(args.rounds):
            for action, run in actions.items():
                for lay in layouts:  # A B C, then A B C again in the next round
                    steps = max(1, args.steps // 8) if action == "rebuild" else args.steps
                    times[lay][action].append(
                        timed(rt, lambda c=built[lay], run=run: run(c), steps)
                    )
        entry = {}
        for lay in layouts:
            cells = built[lay].cells()
            med = {
                a: [1e3 * statistics.median(t[k] for t in times[lay][a]) for k in (0, 1)]
                for a in actions
            }
            entry[lay] = {"cells": cells, "ms": med, "rounds": times[lay]}
            print(
                f"{name:26s} {lay:13s} {cells['band']:7d} {cells['band visited']:8d} "
                + " ".join(f"{m[0]:7.3f}/{m[1]:7.3f}" for m in med.values())
            )
        for lay in layouts[1:]:
            ratio = {
                a: [entry["lists"]["ms"][a][k] / entry[lay]["ms"][a][k] for k in (0, 1)]
                for a in actions
            }
            entry[lay]["speedup over lists"] = ratio
            print(
                f"{'':26s} {lay + ' x':13s} {'':16s} "
                + " ".join(f"{r[0]:7.2f}/{r[1]:7.2f}" for r in ratio.values())
            )
        results["cases"][name] = entry
    print(markdown(results))
    print("whole tracks (default options), wall / CPU ms per frame:")
    results["tracks"] = whole_tracks(rt, args.rounds, LAYOUTS)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
