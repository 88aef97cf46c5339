"""Every candidate's fill of every test region, once per case, on disk: the raw material from
which benchmarks/inpaint_vote_sound.py assembles `auto`'s vote rules and the default's
per-cluster choices without filling again.

    python benchmarks/inpaint_vote_cache.py [--half calibration|test|both] [--every N]

Per case of tests/cases/inpaint_corpus.py (each case one box, the whole image), every
candidate of clpde/inpainting/auto.py fills:

- "hole": the damage alone;
- "ring<w>": the damage and the known pixels within w px of it (w in RINGS);
- "shift<k>": the damage and its clusters' own shapes moved aside in direction k (validate's
  SHIFT test, one direction at a time: down and left).

Stored per case (benchmarks/results/vote_cache/<case>.npz): each fill's values on its
hidden pixels (float32), the hidden masks, the seconds of each fill, and the case's name.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

RINGS = (1, 2, 4, 8)
SHIFTS = (0, 3)  # down and left: two of the four directions, for time
GAP = 3
CACHE = Path(__file__).resolve().parent / "results" / "vote_cache"


def shifted(omega, direction):
    """The hole's clusters (components of the hole grown by 1 px) moved aside along one of
    four directions by twice their half-thickness plus GAP, where they land on known
    pixels at least 2 px from the hole (auto._shifted, one direction): a label image,
    each moved pixel labelled with its cluster (as `ndimage.label` of the grown hole)."""
    known = ~omega
    dist = ndimage.distance_transform_edt(known)
    clusters, count = ndimage.label(dist <= 1, np.ones((3, 3), bool))
    depth = ndimage.distance_transform_edt(omega)
    radius = np.asarray(ndimage.maximum(depth, clusters, np.arange(1, count + 1))).reshape(-1)
    ys, xs = np.nonzero(omega)
    lab = clusters[ys, xs]
    d = np.ceil(2 * radius[lab - 1]).astype(int) + GAP
    dy, dx = ((1, 0), (-1, 0), (0, 1), (0, -1))[direction]
    y, x = ys + dy * d, xs + dx * d
    ny, nx = omega.shape
    keep = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
    out = np.zeros(omega.shape, np.int64)
    y, x, lab = y[keep], x[keep], lab[keep]
    ok = known[y, x] & (dist[y, x] >= 2)
    out[y[ok], x[ok]] = lab[ok]
    return out


def masks(omega):
    """{name: hidden mask} of one case (module docstring)."""
    known = ~omega
    dist = ndimage.distance_transform_edt(known)
    out = {"hole": omega}
    for w in RINGS:
        out[f"ring{w}"] = omega | (known & (dist <= w))
    for k in SHIFTS:
        test = shifted(omega, k) > 0
        if test.any():
            out[f"shift{k}"] = omega | test
    return out


def main(argv=None):
    from clpde import Inpainting
    from clpde.inpainting import auto
    from clpde.runtime import get_runtime

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    parser.add_argument("--every", type=int, default=1)
    parser.add_argument("--offset", type=int, default=0, help="start at this case (with --every)")
    parser.add_argument("--only", default=None, help="comma-separated case names")
    parser.add_argument("--masks", default=None, help="comma-separated tests (hole,ring1,..)")
    args = parser.parse_args(argv)
    runtime = get_runtime()
    names = auto.candidates()
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    cases = [c for c in corpus.build() if c.half in halves][args.offset :: args.every]
    if args.only:
        cases = [c for c in cases if c.name in args.only.split(",")]
    CACHE.mkdir(parents=True, exist_ok=True)
    for i, case in enumerate(cases):
        path = CACHE / f"{case.name.replace('/', '_')}.npz"
        if path.exists():
            continue
        job = Inpainting(case.damaged(), case.mask, channel_axis=case.channel_axis)
        data = job._box_data((0, case.mask.shape[0], 0, case.mask.shape[1]))
        store = {"name": np.array(case.name)}
        start = time.perf_counter()
        for key, hidden in masks(case.mask).items():
            if args.masks and key not in args.masks.split(","):
                continue
            store[f"mask_{key}"] = hidden
            for n in names:
                t0 = time.perf_counter()
                fill = auto._fill(n, data, hidden, runtime, np.float32, 0, {})
                store[f"sec_{key}_{n}"] = np.array(time.perf_counter() - t0)
                store[f"fill_{key}_{n}"] = fill[:, hidden].astype(np.float32)
        tmp = path.with_suffix(".tmp.npz")
        np.savez_compressed(tmp, **store)
        tmp.replace(path)
        print(f"[{i + 1}/{len(cases)}] {case.name} {time.perf_counter() - start:.1f} s", flush=True)


if __name__ == "__main__":
    main()
