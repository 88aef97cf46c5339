"""The ring that bounds each cluster's fill (clpde/inpainting/bounds.py's RING), chosen on the
calibration half of tests/cases/inpaint_corpus.py's corpus, the test half beside it.

    python benchmarks/inpaint_bounds_calibrate.py [--rings 1,2,4,8,0] [--methods default,...]

Each method runs once per case with the bounds off; the bounds of each ring width are then
applied to that fill (the same function api.py applies), and the mean PSNR in the hole per
class and half is printed. Ring 0: no bounds (the fills before bounds.py); a negative
ring: its width, the ranges only (no colour hull).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rings", default="0,2,4,8,16,32,-4,-8,-16")
    parser.add_argument("--methods", default="default,navier-stokes,exemplar")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    import clpde
    from clpde.inpainting import api, bounds

    rings = [int(r) for r in args.rings.split(",")]
    methods = args.methods.split(",")
    # the fills without bounds: api's call replaced by the identity for the run
    real = bounds.limit
    api.bounds.limit = lambda fill, *a, **k: np.array(fill, np.float64)
    table = {}
    try:
        for case in corpus.build(args.quick):
            image = case.damaged()
            for m in methods:
                kw = {} if m == "default" else {"method": m}
                raw = clpde.inpaint(
                    image, case.mask, channel_axis=case.channel_axis, seed=0, progress=False, **kw
                )
                truth = case.truth.astype(np.float64)
                lo, hi = np.nanmin(truth[~case.mask]), np.nanmax(truth[~case.mask])
                scale = (hi - lo) or 1.0

                # [0, 1] units over the known range, channels first, as api.py holds them
                def planes(a, lo=lo, scale=scale):
                    a = (np.asarray(a, np.float64) - lo) / scale
                    return a[None] if a.ndim == 2 else np.moveaxis(a, -1, 0)

                known = np.nan_to_num(planes(image))
                for r in rings:
                    if r == 0:
                        out = np.asarray(raw, np.float64)
                    else:
                        lim = (
                            real(planes(raw), known, case.mask, ring=abs(r), hull=r > 0) * scale
                            + lo
                        )
                        lim = lim[0] if raw.ndim == 2 else np.moveaxis(lim, 0, -1)
                        out = np.rint(lim) if case.kind != "float" else lim
                    key = (m, r, case.half, case.damage)
                    table.setdefault(key, []).append(corpus.psnr(case, out))
            print(case.name, flush=True)
    finally:
        api.bounds.limit = real
    for half in ("calibration", "test"):
        print(f"\n{half}: mean PSNR in the hole, dB, per ring width (0: no bounds)")
        print(
            f"{'method':15s} {'ring':>4s}"
            + "".join(f"{d:>11s}" for d in corpus.CLASSES)
            + "       mean"
        )
        for m in methods:
            for r in rings:
                row = [np.mean(table.get((m, r, half, d), [np.nan])) for d in corpus.CLASSES]
                print(
                    f"{m:15s} {r:4d}"
                    + "".join(f"{v:11.2f}" for v in row)
                    + f"{np.nanmean(row):11.3f}"
                )


if __name__ == "__main__":
    main()
