"""Is `method="auto"`'s vote sound? Its result against its best candidate, case by case, for
the ways of pooling the ring's evidence (clpde/inpainting/auto.py: PRIOR, blend, SCALE),
on tests/cases/inpaint_corpus.py's corpus, the calibration half to choose, the test half
beside it.

    python benchmarks/inpaint_vote_rules.py [--half calibration|test|both] [--every N]

Each case is one box (the whole 128 x 128 image); every candidate's fill of the hole and of
each hidden ring is computed once (memoised) and every rule assembled from them. Printed
per rule and half: the mean PSNR over the classes, the worst case's margin to the best
single candidate (dB; the issue's bound: -0.2), how many cases fall below -0.2 dB, and the
fills' time (candidates: their own fill; rules: every fill they use, both runs).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

PRIORS = (0.0, 100.0, 300.0, float("inf"))
SCALES = (0.0, 0.5, 1.0)  # the ring's width per cluster: SCALE x its half-thickness, 2..8
# --default: the default's vote between a smooth fill and the spectral one, on the clusters
# at least THIN px thick (half-thickness; 0: every cluster); the rest keep the spectral fill
DEFAULT_NAMES = ("biharmonic", "spectral")
THINS = (0.0, 3.0, 6.0)


def _bool(v):
    return v in ("1", "True", "true")


def main(argv=None):
    from clpde import Inpainting
    from clpde.inpainting import auto
    from clpde.runtime import get_runtime

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    parser.add_argument("--every", type=int, default=1)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--default", action="store_true", help="the default's vote (THINS)")
    parser.add_argument("--rules", default=None, help="scale/blend/prior/thin/shift;...")
    parser.add_argument("--ring", type=int, default=None, help="auto.RING (the narrowest)")
    parser.add_argument(
        "--json", type=Path, default=Path(__file__).resolve().parent / "results" / "vote_rules.json"
    )
    args = parser.parse_args(argv)
    runtime = get_runtime()
    if args.ring is not None:
        auto.RING = args.ring
    names = auto.candidates(DEFAULT_NAMES if args.default else None)
    cache, seconds = {}, {}
    original = auto._fill

    def memo(name, data, omega, runtime, dtype, seed, params):
        key = (name, hashlib.sha1(np.packbits(omega).tobytes()).hexdigest())
        if key not in cache:
            start = time.perf_counter()
            cache[key] = original(name, data, omega, runtime, dtype, seed, params)
            seconds[key] = time.perf_counter() - start
        used.add(key)
        return cache[key]

    used = set()

    auto._fill = memo
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    cases = [c for c in corpus.build(args.quick) if c.half in halves][:: args.every]
    configs = [(s, b, p, 0.0, False) for s in SCALES for b in (True, False) for p in PRIORS]
    configs += [(0.0, b, p, 0.0, True) for b in (True, False) for p in PRIORS]
    if args.rules:  # a subset, as "scale/blend/prior/thin/shift;..."
        configs = [
            tuple(
                t(v) for t, v in zip((float, _bool, float, float, _bool), c.split("/"), strict=True)
            )
            for c in args.rules.split(";")
        ]
    if args.default:
        configs = [(s, True, 300.0, t, False) for s in (0.0, 0.5) for t in THINS]
    spent = {}
    rows = []  # (half, damage, case, config or candidate, psnr)
    for i, case in enumerate(cases):
        cache.clear()
        seconds.clear()
        job = Inpainting(case.damaged(), case.mask, channel_axis=case.channel_axis)
        box = (0, case.mask.shape[0], 0, case.mask.shape[1])
        data = job._box_data(box)

        def score(filled, case=case, job=job, box=box):
            out = case.damaged().copy()
            job._write(out, box, filled, case.mask)
            return corpus.psnr(case, out)

        single = {}
        for n in names:
            used.clear()
            single[n] = score(memo(n, data, case.mask, runtime, np.float32, 0, {}))
            spent[n] = spent.get(n, 0.0) + sum(seconds[k] for k in used)
        best = max(single.values())
        for n, p in single.items():
            rows.append((case.half, case.damage, case.name, n, p, p - best))
        for cfg in configs:
            scale, blend, prior, thin, shift = cfg
            used.clear()
            filled, _ = auto.choose(
                data,
                case.mask,
                runtime,
                names=names,
                scale=scale,
                blend=blend,
                prior=prior,
                thin=thin,
                shift=shift,
                seed=0,
            )
            spent[cfg] = spent.get(cfg, 0.0) + sum(seconds[k] for k in used)
            p = score(filled)
            rows.append((case.half, case.damage, case.name, cfg, p, p - best))
        print(f"[{i + 1}/{len(cases)}] {case.name}", flush=True)
    auto._fill = original
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps([[*r[:3], str(r[3]), *r[4:]] for r in rows]))
    for half in halves:
        print(
            f"\n{half}: rule (scale, blend, prior, thin, shift) | mean over classes | worst margin "
            "to the best candidate | cases below -0.2 dB | per class mean"
        )
        keys = list(dict.fromkeys(r[3] for r in rows))
        for k in keys:
            sel = [r for r in rows if r[0] == half and r[3] == k]
            if not sel:
                continue
            by = {}
            for r in sel:
                by.setdefault(r[1], []).append(r[4])
            means = {d: np.mean(v) for d, v in by.items()}
            worst = min(sel, key=lambda r: r[5])
            below = sum(r[5] < -0.2 for r in sel)
            print(
                f"{str(k):28s} {spent.get(k, math.nan):6.1f}s "
                f"{np.mean(list(means.values())):7.2f} {worst[5]:+7.2f} "
                f"({worst[2]}) {below:3d}  "
                + " ".join(f"{d[:5]}={means[d]:.2f}" for d in corpus.CLASSES if d in means)
            )


if __name__ == "__main__":
    main()
