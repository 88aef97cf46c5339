"""Why blotches are missed: the film detector's stages, replayed on the CALIBRATION half of
benchmarks/film_corpus.py, with each truly damaged blotch pixel that is not called a blotch
put down to the first stage that loses it.

    PYTHONPATH=. python benchmarks/film_missed.py [--frames 12] [--half calibration] [--fill]

Causes, in the detector's order: an end frame (its stages reported apart); no trusted
neighbour on one side (no temporal evidence: the motion is not trusted there); evidence
below the hysteresis's low level (split by the pixel's true change: faint < 15 grey
levels, 15-30, > 30); a region that never reaches the high level; beside a scratch; a
region smaller than CELLS of the grain's correlation areas; the ring check; the local
noise check; the tail check; the motion check (found again nearby); called a scratch.
With --fill, the found blotch pixels the fill leaves as they were (its self-check refusing
the repair, or keep) are counted too.
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np
from film_corpus import corpus
from scipy import ndimage

import clpde
from clpde.film import _regions as regions
from clpde.film import detect as fdet
from clpde.film._grow import REGION_LOW
from clpde.film._planes import film_planes, grey
from clpde.film.lines import scratch_runs
from clpde.film.stream import KEEP


def stages(G, sc, t, bthr, sthr, search, min_length, gamma):
    """_frame_kinds' blotch masks after each stage (the same calls, in the same order)."""
    zc, res, sig = sc["zc"], sc["res"], sc["sigma"]
    scratch = scratch_runs(zc[t], sc["least"][t], sig[t], sthr, min_length)
    (a, zr), r = fdet.blotch_evidence(sc, t, gamma, fdet.HYSTERESIS_LOW * bthr), res[t]
    low = (a > fdet.HYSTERESIS_LOW * bthr) | (zr > REGION_LOW * bthr)
    out = {"a": a, "low": low}
    b, a = fdet._regions_found(a, zr, r, sc["region_noise"][t], bthr)
    out["hyst"] = b
    b = b & ~ndimage.binary_dilation(scratch)
    out["scratch"] = b
    b = fdet._no_singletons(b, max(fdet.SMALLEST, fdet.CELLS * sc["region_noise"][t][1]))
    out["single"] = b
    b = regions._ring_check(b, sc["both"][t], r, sig[t], sc["flows"][t], sc["bridge"][t])
    out["ring"] = b
    b = regions._local_noise_check(b, a, r, sig[t], bthr)
    out["local"] = b
    busy = ndimage.binary_dilation(b | scratch, iterations=2)
    b = regions._tail_check(b, busy, r, sc["region_noise"][t][1], sc["both"][t])
    out["tail"] = b
    b = regions._motion_check(b, G, t, res[t], search, sig[t], bthr)
    out["motion"] = b
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--half", default="calibration")
    ap.add_argument("--fill", action="store_true", help="also count found pixels left unfilled")
    args = ap.parse_args()
    total = Counter()
    found_total = kept_total = 0
    for c in corpus(args.half, frames=args.frames):
        G = grey(film_planes(c["dirty"], -1)[0])
        T, ny, nx = G.shape
        sc = fdet.film_scores(G, None, 2)
        kinds = fdet.film_kinds(
            G, sc, fdet.BLOTCH_THRESHOLD, fdet.SCRATCH_THRESHOLD, 24, max(24, int(0.4 * ny))
        )
        amp = np.abs(c["dirty"].astype(int) - c["clean"].astype(int)).max(-1)
        if args.fill:
            # found, but left as it was by the fill: refused by its self-check (or changed by
            # less than keep's noise units)
            out = clpde.inpaint_video(
                c["dirty"], kinds > 0, channel_axis=-1, keep=KEEP, kinds=kinds
            )
            same = (out == c["dirty"]).all(-1)
            kept_total += int((same & (kinds == 1) & (c["truth"] == 1) & ~c["spare"]).sum())
        cnt = Counter()
        for t in range(T):
            gt = (c["truth"][t] == 1) & ~c["spare"][t]
            st = stages(
                G,
                sc,
                t,
                fdet.BLOTCH_THRESHOLD,
                fdet.SCRATCH_THRESHOLD,
                24,
                max(24, int(0.4 * ny)),
                fdet.GAMMA,
            )
            miss = gt & (kinds[t] != 1)
            found_total += int((gt & (kinds[t] == 1)).sum())
            end = "end " if t in (0, T - 1) else ""
            causes = [("not trusted both sides", ~sc["both"][t])]
            for lo, hi, nm in ((0, 15, "<15"), (15, 30, "15-30"), (30, 999, ">30")):
                causes.append((f"below low, amp {nm}", ~st["low"] & (amp[t] >= lo) & (amp[t] < hi)))
            causes += [
                ("region below high", ~st["hyst"]),
                ("beside scratch", ~st["scratch"]),
                ("smaller than CELLS grain areas", ~st["single"]),
                ("ring check", ~st["ring"]),
                ("local noise check", ~st["local"]),
                ("tail check", ~st["tail"]),
                ("motion check", ~st["motion"]),
                ("called scratch", kinds[t] == 2),
                ("other", np.ones_like(miss)),
            ]
            left = miss.copy()
            for name, sel in causes:
                cnt[end + name] += int((left & sel).sum())
                left &= ~sel
        n = sum(cnt.values())
        print(c["name"], n, {k: v for k, v in sorted(cnt.items())}, flush=True)
        total += cnt
    n = sum(total.values())
    print(f"{args.half}: found {found_total}, missed {n}")
    if args.fill:
        print(f"  found but left unfilled by the fill (self-check, keep): {kept_total}")
    for k, v in sorted(total.items(), key=lambda kv: -kv[1]):
        print(f"  {k}: {v} ({100 * v / n:.1f}%)")


if __name__ == "__main__":
    main()
