"""method="pick" against the spectral fill (today's default) on tests/cases/inpaint_corpus.py's
corpus: mean PSNR in the hole and time per class, both halves (calibration / test).

    python benchmarks/inpaint_pick_time.py [--runs 2] [--half both] [--classes blobs,...] [--smooth]

Per case each method runs `runs` times, interleaved (spectral, pick, spectral, pick, ...),
after one warm-up call per method that builds the kernels; its time is the least of its
runs' `info.seconds` (the fill's, without the build), so that a busy machine's stalls count
less. Printed per class and half: mean PSNR of each, their sum of times and the ratio.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

METHODS = ("spectral", "pick")


def main(argv=None):
    import clpde

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--half", default="both")
    parser.add_argument("--classes", default=None, help="comma-separated classes only")
    parser.add_argument("--smooth", action="store_true", help="pick with its smooth vote")
    args = parser.parse_args(argv)
    extra = {"pick": {"smooth": True} if args.smooth else {}, "spectral": {}}
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    cases = [c for c in corpus.build() if c.half in halves]
    if args.classes:
        cases = [c for c in cases if c.damage in args.classes.split(",")]
    rows = []
    warm = cases[0]
    for m in METHODS:
        clpde.inpaint(
            warm.damaged(),
            warm.mask,
            channel_axis=warm.channel_axis,
            method=m,
            progress=False,
            seed=0,
            **extra[m],
        )
    for i, c in enumerate(cases):
        best = {m: np.inf for m in METHODS}
        score = {}
        for _ in range(args.runs):
            for m in METHODS:
                out, info = clpde.inpaint(
                    c.damaged(),
                    c.mask,
                    channel_axis=c.channel_axis,
                    method=m,
                    **extra[m],
                    return_info=True,
                    progress=False,
                    seed=0,
                )
                best[m] = min(best[m], info.seconds)
                score[m] = corpus.psnr(c, out)
        rows.append((c.half, c.damage, c.name, score, best))
        print(
            f"[{i + 1}/{len(cases)}] {c.name} "
            + " ".join(f"{m} {score[m]:.2f} dB {best[m]:.2f} s" for m in METHODS),
            flush=True,
        )
    print(f"\n{'class':12s} " + " | ".join(f"{h:^44s}" for h in halves))
    print(
        f"{'':12s} "
        + " | ".join(
            f"{'spectral dB':>11s} {'pick dB':>8s} {'spectral s':>10s} {'pick s':>7s} {'ratio':>5s}"
            for _ in halves
        )
    )
    for d in corpus.CLASSES:
        cells = []
        for h in halves:
            sel = [r for r in rows if r[0] == h and r[1] == d]
            if not sel:
                cells.append(" " * 44)
                continue
            ps = {m: np.mean([r[3][m] for r in sel]) for m in METHODS}
            ts = {m: sum(r[4][m] for r in sel) for m in METHODS}
            cells.append(
                f"{ps['spectral']:11.2f} {ps['pick']:8.2f} {ts['spectral']:10.2f} "
                f"{ts['pick']:7.2f} {ts['pick'] / ts['spectral']:5.2f}"
            )
        print(f"{d:12s} " + " | ".join(cells))
    for h in halves:
        sel = [r for r in rows if r[0] == h]
        t = {m: sum(r[4][m] for r in sel) for m in METHODS}
        print(
            f"{h}: total spectral {t['spectral']:.1f} s, pick {t['pick']:.1f} s, "
            f"ratio {t['pick'] / t['spectral']:.2f}"
        )


if __name__ == "__main__":
    main()
