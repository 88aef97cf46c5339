"""Do no harm on the real-footage corpus, detection and fill only (no peers): per clip and
per half, PSNR whole / damaged pixels, harm (worst frame, worst end frame), frames made
worse than their damaged input, and blotch and scratch precision / recall.

    PYTHONPATH=. python benchmarks/film_harm.py [--frames 12] [--half calibration]

(PYTHONPATH=.: from a checkout, the checkout's clpde rather than an installed one.)

The quick check behind the do-no-harm changes of issue 34 (benchmarks/film.py has the full
tables with the peers).
"""

from __future__ import annotations

import argparse
import time

from film import Counts, Quality
from film_corpus import corpus

import clpde
from clpde.film.stream import KEEP


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--half", choices=("test", "calibration"), help="one half only")
    args = ap.parse_args()
    for half in (args.half,) if args.half else ("test", "calibration"):
        q, cb, cs = Quality(), Counts(), Counts()
        detect = fill = 0.0
        for c in corpus(half, frames=args.frames):
            d, truth, spare = c["dirty"], c["truth"], c["spare"]
            t0 = time.perf_counter()
            mask, kinds = clpde.detect_defects(d, channel_axis=-1, return_kinds=True)
            t1 = time.perf_counter()
            out = clpde.inpaint_video(d, mask, channel_axis=-1, keep=KEEP, kinds=kinds)
            detect, fill = detect + t1 - t0, fill + time.perf_counter() - t1
            one = Quality()
            one.add(out, c)
            q.add(out, c)
            cb.add(kinds == 1, truth == 1, truth == 2, spare)
            cs.add(kinds == 2, truth == 2, truth == 1, spare)
            print(f"  {c['name']}: {one.row()}", flush=True)
        (bp, br), (sp, sr) = cb.pr(), cs.pr()
        print(
            f"{half}: PSNR whole | damaged | harm worst | harm ends | worse: {q.row()}; "
            f"blotch P/R {bp:.3f}/{br:.3f}, scratch P/R {sp:.3f}/{sr:.3f}; "
            f"detect {detect:.0f} s, fill {fill:.0f} s",
            flush=True,
        )


if __name__ == "__main__":
    main()
