"""Calibration of the self-validated default (clpde/inpainting/auto.py) on the calibration
half of tests/cases/inpaint_corpus.py's corpus, and nothing else.

    python benchmarks/inpaint_validate_calibrate.py [--quick] [--every N] [--json PATH]

The parameters: the candidate set (SETS, among SUPERSET),
the ring's width (RINGS) and blend or pick. Each case's fills are computed once per
candidate and hidden mask (memoised), so every configuration is then assembled from them.
A configuration's score is its mean PSNR in the hole over the classes (each class weighs
the same), and its time the sum of its candidates' fill times (both runs). The table lists
the best configurations, and, for each candidate set, its best ring; auto.py's
CANDIDATES and RING are set from the chosen line by hand.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

SUPERSET = ("biharmonic", "coherence", "transport", "navier-stokes", "exemplar", "spectral")
RINGS = (1, 2, 4)
# the candidate sets tried: the cheap structure pair, then the texture and frequency models
# added to it, then each of the slower PDE methods on top
SETS = (
    ("biharmonic", "coherence"),
    ("biharmonic", "coherence", "exemplar"),
    ("biharmonic", "coherence", "spectral"),
    ("biharmonic", "coherence", "exemplar", "spectral"),
    ("biharmonic", "coherence", "transport", "exemplar", "spectral"),
    ("biharmonic", "coherence", "navier-stokes", "exemplar", "spectral"),
    ("biharmonic", "spectral"),
    ("biharmonic", "exemplar", "spectral"),
)
RESULTS = Path(__file__).resolve().parent / "results" / "inpaint_validate_calibrate.json"


def main(argv=None):
    from clpde import Inpainting
    from clpde.inpainting import auto
    from clpde.runtime import get_runtime

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument(
        "--every",
        type=int,
        default=1,
        help="every Nth case of the calibration half (a shorter run)",
    )
    parser.add_argument("--json", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    runtime = get_runtime()
    names = auto.candidates(SUPERSET)
    cache, seconds = {}, {}
    original = auto._fill

    def memo(name, data, omega, runtime, dtype, seed, params):
        key = (
            name,
            hashlib.sha1(np.packbits(omega).tobytes()).hexdigest(),
            hashlib.sha1(data.tobytes()).hexdigest(),
        )
        if key not in cache:
            start = time.perf_counter()
            cache[key] = original(name, data, omega, runtime, dtype, seed, params)
            seconds[key] = time.perf_counter() - start
        return cache[key]

    auto._fill = memo
    cases = [c for c in corpus.build(args.quick) if c.half == "calibration"][:: args.every]
    configs = [
        (subset, ring, blend)
        for subset in SETS
        if set(subset) <= set(names)
        for ring in RINGS
        for blend in (True, False)
    ]
    scores = {cfg: {} for cfg in configs}
    times = {cfg: 0.0 for cfg in configs}
    for i, case in enumerate(cases):
        cache.clear()
        seconds.clear()
        job = Inpainting(case.damaged(), case.mask, channel_axis=case.channel_axis)
        data = job._box_data((0, case.mask.shape[0], 0, case.mask.shape[1]))
        start = time.perf_counter()
        for cfg in configs:
            subset, ring, blend = cfg
            used = []
            orig_memo = auto._fill

            def tracking(name, d, o, *a, _orig=orig_memo, _used=used):
                key = (name, hashlib.sha1(np.packbits(o).tobytes()).hexdigest())
                _used.append(key)
                return _orig(name, d, o, *a)

            auto._fill = tracking
            filled, _ = auto.choose(
                data, case.mask, runtime, names=subset, ring=ring, blend=blend, seed=0
            )
            auto._fill = orig_memo
            out = case.damaged().copy()
            job._write(out, (0, case.mask.shape[0], 0, case.mask.shape[1]), filled, case.mask)
            scores[cfg][case.name] = (case.damage, corpus.psnr(case, out))
            times[cfg] += sum(v for k, v in seconds.items() if k[:2] in set(used))
        print(f"[{i + 1}/{len(cases)}] {case.name} {time.perf_counter() - start:.1f} s", flush=True)
    auto._fill = original
    table = []
    for cfg in configs:
        by_class = {}
        for damage, p in scores[cfg].values():
            by_class.setdefault(damage, []).append(p)
        means = {d: float(np.mean(v)) for d, v in by_class.items()}
        table.append(
            {
                "candidates": list(cfg[0]),
                "ring": cfg[1],
                "blend": cfg[2],
                "score": float(np.mean(list(means.values()))),
                "classes": means,
                "seconds": times[cfg],
            }
        )
    table.sort(key=lambda r: -r["score"])
    classes = [d for d in corpus.CLASSES if d in table[0]["classes"]]
    print(
        f"\n{'candidates':52s} {'ring':>4s} {'blend':>5s} {'mean':>6s} {'s':>6s} "
        + " ".join(f"{d[:7]:>7s}" for d in classes)
    )

    def line(r):
        return (
            f"{'+'.join(r['candidates']):52s} {r['ring']:4d} {str(r['blend']):>5s} "
            f"{r['score']:6.2f} {r['seconds']:6.1f} "
            + " ".join(f"{r['classes'][d]:7.2f}" for d in classes)
        )

    for r in table[:15]:
        print(line(r))
    print("\nbest ring per candidate set:")
    seen = set()
    for r in table:
        key = (tuple(r["candidates"]), r["blend"])
        if key not in seen:
            seen.add(key)
            print(line(r))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(table, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
