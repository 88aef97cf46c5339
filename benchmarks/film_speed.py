"""Film restoration speed at 640x360 colour: frames per second through the sliding window
(the path of `clpde restore`), on vtest.avi cropped to 640x360 with the corpus's damage.

    python benchmarks/film_speed.py [--frames 24] [--repeat N] [--block 32] [--digest]

--repeat N concatenates the clip N times (a long film: memory stays one window). Prints
the detection and fill seconds per frame measured inside the window work, the frames per
second of the whole run, and where the detector's time goes (flows, the rest).

The machine may be shared, and then the wall time says more about the other jobs than about
this one. So the run also reports what does not depend on them:

- the CPU seconds a frame (every thread), and the calling thread's own (the serial part: it
  waits while the window's frames run in threads, and then uses none);
- how many of the process's threads wanted a core, sampled every 4 ms from /proc (state R:
  running or waiting for a core): given two free cores, the run would keep min(2, that)
  busy, so ``cores busy if given 2`` (their mean over the samples with work) and ``frames/s
  if given 2`` (that over the CPU seconds a frame) estimate an idle machine's figures. They
  are estimates: a busy machine also slows each core (caches), so the CPU seconds read high;
- the load average (1 minute) before and after.

--digest prints a SHA-256 of the restored frames, masks and kinds, to check that a change
meant for speed leaves the results bit for bit as they were.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import os
import threading
import time
from collections import Counter

import numpy as np
from film_corpus import damage_clip, grain_flicker, read_clip

import clpde
from clpde.film.stream import DEFAULT_BLOCK, film_work, restore_stream
from clpde.motion import dis


def clip(frames):
    raw = read_clip("vtest.avi", 100, frames, None)[:, 108:468, 64:704]
    rng = np.random.default_rng(7)
    clean = grain_flicker(raw, rng)
    dirty, truth, _ = damage_clip(clean, rng)
    return dirty, truth


class Demand:
    """How many of this process's other threads are in state R, sampled every `period` s."""

    def __init__(self, period: float = 0.004) -> None:
        self.period, self.counts = period, Counter()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        me = str(threading.get_native_id())
        while not self._stop.is_set():
            wanting = 0
            for tid in os.listdir("/proc/self/task"):
                try:
                    with open(f"/proc/self/task/{tid}/stat") as f:
                        state = f.read().rsplit(")", 1)[1].split()[0]
                except OSError:  # the thread ended meanwhile
                    continue
                wanting += tid != me and state == "R"
            self.counts[wanting] += 1
            time.sleep(self.period)

    def __enter__(self) -> Demand:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()

    def cores_if_given(self, cores: int = 2) -> float:
        """The mean of min(cores, threads wanting one) over the samples with work."""
        work = {k: n for k, n in self.counts.items() if k > 0}
        return sum(min(k, cores) * n for k, n in work.items()) / max(sum(work.values()), 1)


def load() -> float:
    return os.getloadavg()[0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--block", type=int, default=DEFAULT_BLOCK)
    ap.add_argument("--digest", action="store_true")
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

    def fill(frames, masks, channel_axis=None, **given):  # the kinds, where the work takes them
        t0 = time.perf_counter()
        out = base.fill(frames, masks, channel_axis=channel_axis, **given)
        spent["fill"] += time.perf_counter() - t0
        return out

    work = dataclasses.replace(base, fill=fill, detect=detect)  # clpde restore's work, timed
    digest = hashlib.sha256()
    load0 = load()
    t0, c0, m0 = time.perf_counter(), time.process_time(), time.thread_time()
    n = 0
    with Demand() as demand:
        for frame, mask, kinds in restore_stream(film, len(film), work, block=args.block):
            n += 1
            if args.digest:
                for part in (frame, mask, kinds):
                    digest.update(np.ascontiguousarray(part).tobytes())
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    serial = time.thread_time() - m0
    print(f"{n} frames of 640x360 colour in {wall:.1f} s: {n / wall:.2f} frames/s")
    # the machine may be shared: the CPU seconds (all threads) say what the work costs
    print(f"CPU {cpu / n:.3f} s per frame (all threads; {cpu / wall:.2f} cores busy on average)")
    print(f"of which the calling thread's own (serial) {serial / n:.3f} s per frame")
    given = demand.cores_if_given(2)
    print(
        f"threads wanting a core: {given:.2f} cores busy if given 2 (estimate), so "
        f"{given / (cpu / n):.2f} frames/s if given 2 cores (estimate); "
        f"load average {load0:.1f} before, {load():.1f} after"
    )
    print(
        f"per frame: detect {spent['detect'] / n:.3f} s, fill {spent['fill'] / n:.3f} s, "
        f"of which DIS flows {spent['flow'] / n:.3f} s"
    )
    print(f"clpde {clpde.__version__}, DIS preset {dis.PRESET}")
    if args.digest:
        print(f"digest {digest.hexdigest()}")


if __name__ == "__main__":
    main()
