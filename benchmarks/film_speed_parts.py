"""Where a film frame's time goes: film_speed's clip restored in ONE thread (the window's
frame threads and OpenCV's limited to one), each part's CPU seconds of the calling thread,
inclusive (a part's flows and warps count in it too), per frame.

    PYTHONPATH=. python benchmarks/film_speed_parts.py [--frames 16]

One thread, so that each part's time is its own and not another thread's waiting; the
spatial fallback's kernels run in PoCL's threads: their device time is what CLPDE_PROFILE=1
prints. The parts are looked up by name, and a part that a tree does not have is left out
(the same script runs against an older tree).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import os
import time
from collections import defaultdict

# (module, attribute) of each part, outermost first
PARTS = [
    ("clpde.film.stream", "restore_window"),
    ("clpde.film.detect", "detect_defects"),
    ("clpde.film.detect", "frame_scores"),
    ("clpde.film.detect", "film_kinds"),
    ("clpde.film.fill", "inpaint_video"),
    ("clpde.film.fill", "_temporal"),
    ("clpde.film.fill", "_spatial_crops"),
    ("clpde.film._motion", "FilmMotion.trusted"),
    ("clpde.film._compensate", "fit_gain"),
    ("clpde.motion.dis", "DisFlow.flow"),
    ("clpde.motion.dis", "DisFlow.warp"),
    ("clpde.motion.dis", "DisFlow.remap"),
    ("clpde.film._planes", "film_planes"),
    ("clpde.film._planes", "FilmLayout.restore"),
    ("clpde.film._planes", "FilmLayout.restore_changed"),
]


def instrument(spent: dict, calls: dict) -> None:
    """Wrap each part (and every module's own name for it) with a thread-time counter."""
    for module, name in PARTS:
        owner = importlib.import_module(module)
        path = name.split(".")
        for part in path[:-1]:
            owner = getattr(owner, part)
        real = getattr(owner, path[-1], None)
        if real is None:
            continue

        def timed(*args, _real=real, _name=name, **kwargs):
            start = time.thread_time()
            try:
                return _real(*args, **kwargs)
            finally:
                spent[_name] += time.thread_time() - start
                calls[_name] += 1

        functools.update_wrapper(timed, real)
        setattr(owner, path[-1], timed)
        if len(path) == 1:  # functions imported by name into other film modules
            for other in ("detect", "fill", "stream", "_motion", "lines"):
                mod = importlib.import_module(f"clpde.film.{other}")
                if getattr(mod, name, None) is real:
                    setattr(mod, name, timed)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=16)
    args = ap.parse_args()
    os.cpu_count = lambda: 1  # map_frames: one thread
    import cv2

    cv2.setNumThreads(1)
    from film_speed import clip

    from clpde.film.stream import film_work, restore_stream

    spent, calls = defaultdict(float), defaultdict(int)
    instrument(spent, calls)
    dirty, _ = clip(args.frames)
    start = time.process_time()
    n = sum(1 for _ in restore_stream(dirty, len(dirty), film_work()))
    cpu = time.process_time() - start
    print(f"{n} frames of 640x360 colour, one thread: {cpu / n * 1e3:.0f} ms CPU a frame")
    for name, seconds in sorted(spent.items(), key=lambda item: -item[1]):
        print(f"{seconds / n * 1e3:8.1f} ms a frame {calls[name]:6d} calls  {name}")


if __name__ == "__main__":
    main()
