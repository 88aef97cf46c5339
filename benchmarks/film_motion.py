"""The film's motion source, side by side: OpenCV's DIS presets against clpde.motion's
device solver (with the film's parameters), on the real clips of benchmarks/film_corpus.py.

    python benchmarks/film_motion.py [--frames 8]

For each pair (t, t + 1) and (t, t + 2) of each clip the flow is estimated on the DAMAGED
frames (as the restoration must), the CLEAN neighbour is warped with it onto frame t and
compared with the clean frame t: mean absolute difference in grey levels over the pixels
whose match stays inside the frame, and the share of pixels off by more than 10 levels.
Both halves are printed; seconds per flow are for 640x360 (a vtest frame resized).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from film_corpus import corpus, read_clip

from clpde.film._compensate import FILM_FLOW
from clpde.motion.dis import PRESETS, DisFlow, to_u8
from clpde.motion.flow import FlowSolver, default_levels


def _grey(x):
    return x.astype(np.float32).mean(-1) / 255.0


class Device:
    def __init__(self):
        import pyopencl.array as cla

        self.cla = cla
        self.solver = FlowSolver(None, FILM_FLOW)

    def flow(self, a, b):
        q = self.solver.rt.queue
        ny, nx = a.shape
        one = self.cla.to_device(q, np.ones((ny, nx), np.float32))
        u, v = self.solver.flow(
            self.cla.to_device(q, a),
            self.cla.to_device(q, b),
            one,
            one,
            default_levels(ny, nx),
        )
        return np.stack([u.get(), v.get()], -1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--no-device", action="store_true")
    args = ap.parse_args()
    warper = DisFlow()
    methods = {f"DIS {p}": DisFlow(p) for p in PRESETS}
    if not args.no_device:
        methods["clpde.motion (device, film params)"] = Device()
    for half in ("test", "calibration"):
        clips = corpus(half, frames=args.frames)
        print(f"\n{half} half ({len(clips)} clips, {args.frames} frames each)")
        print("| motion | mean abs diff (levels) | share > 10 levels |")
        print("|---|---|---|")
        for name, m in methods.items():
            err, bad, n = 0.0, 0, 0
            for c in clips:
                gd = [_grey(f) for f in c["dirty"]]
                gc = [_grey(f) for f in c["clean"]]
                T = len(gd)
                for t in range(T):
                    for k in (1, 2):
                        if t + k >= T:
                            continue
                        a, b = gd[t], gd[t + k]
                        f = m.flow(to_u8(a), to_u8(b)) if name.startswith("DIS") else m.flow(a, b)
                        w = warper.warp(gc[t + k], np.ascontiguousarray(f, np.float32))
                        ny, nx = a.shape
                        gy, gx = np.mgrid[0:ny, 0:nx]
                        xs, ys = gx + f[..., 0], gy + f[..., 1]
                        ok = (xs >= 0) & (xs <= nx - 1) & (ys >= 0) & (ys <= ny - 1)
                        d = np.abs(w - gc[t])[ok] * 255
                        err += float(d.sum())
                        bad += int((d > 10).sum())
                        n += d.size
            print(f"| {name} | {err / n:.2f} | {100 * bad / n:.2f}% |")
    big = read_clip("vtest.avi", 0, 3, None)[:, 108:468, 64:704]
    a, b = to_u8(_grey(big[0])), to_u8(_grey(big[1]))
    print("\nseconds per flow, 640x360:")
    for name, m in methods.items():
        x, y = (a, b) if name.startswith("DIS") else (_grey(big[0]), _grey(big[1]))
        m.flow(x, y)
        t0 = time.perf_counter()
        for _ in range(3):
            m.flow(x, y)
        print(f"  {name}: {(time.perf_counter() - t0) / 3:.3f}")


if __name__ == "__main__":
    main()
