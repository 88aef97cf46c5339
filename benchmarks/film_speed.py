"""Film restoration speed at 640x360 colour: frames per second through the sliding window
(the path of `clpde restore`), on vtest.avi cropped to 640x360 with the corpus's damage.

    python benchmarks/film_speed.py [--frames 24] [--repeat N]

--repeat N concatenates the clip N times (a long film: memory stays one window). Prints
the detection and fill seconds per frame measured inside the window work, the frames per
second of the whole run, and where the detector's time goes (flows, the rest).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from film_corpus import damage_clip, grain_flicker, read_clip

import clpde
from clpde.film.stream import WindowWork, film_work, restore_stream
from clpde.motion import dis


def clip(frames):
    raw = read_clip("vtest.avi", 100, frames, None)[:, 108:468, 64:704]
    rng = np.random.default_rng(7)
    clean = grain_flicker(raw, rng)
    dirty, truth, _ = damage_clip(clean, rng)
    return dirty, truth


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    dirty, _ = clip(args.frames)
    film = np.concatenate([dirty] * args.repeat)
    base = film_work()
    spent = {"detect": 0.0, "fill": 0.0, "flow": 0.0}
    real_flow = dis.DisFlow.flow

    def timed_flow(self, a, b):
        t0 = time.perf_counter()
        out = real_flow(self, a, b)
        spent["flow"] += time.perf_counter() - t0
        return out

    dis.DisFlow.flow = timed_flow

    def detect(frames, channel_axis=None):
        t0 = time.perf_counter()
        out = base.detect(frames, channel_axis=channel_axis)
        spent["detect"] += time.perf_counter() - t0
        return out

    def fill(frames, masks, channel_axis=None):
        t0 = time.perf_counter()
        out = base.fill(frames, masks, channel_axis=channel_axis)
        spent["fill"] += time.perf_counter() - t0
        return out

    work = WindowWork(fill, detect, base.fill_radius, base.detect_radius)
    t0, c0 = time.perf_counter(), time.process_time()
    n = sum(1 for _ in restore_stream(film, len(film), work))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(f"{n} frames of 640x360 colour in {wall:.1f} s: {n / wall:.2f} frames/s")
    # the machine may be shared: the CPU seconds (all threads) say what the work costs
    print(f"CPU {cpu / n:.3f} s per frame (all threads; {cpu / wall:.2f} cores busy on average)")
    print(
        f"per frame: detect {spent['detect'] / n:.3f} s, fill {spent['fill'] / n:.3f} s, "
        f"of which DIS flows {spent['flow'] / n:.3f} s"
    )
    print(f"clpde {clpde.__version__}, DIS preset {dis.PRESET}")


if __name__ == "__main__":
    main()
