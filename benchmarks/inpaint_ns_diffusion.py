"""How navier-stokes's vorticity diffusion should grow with the hole: on one half of
tests/cases/inpaint_corpus.py, clpde's navier-stokes with nu = 0.05 max(1, r / r0)^p per
case (r the mask's largest distance to a known pixel), scored as
benchmarks/inpaint_generalise.py scores (mean PSNR in the hole per class).

    PYTHONPATH=. python benchmarks/inpaint_ns_diffusion.py [--half calibration]

The rule taken (r0 3, p 2: clpde.inpainting.navier_stokes.scaled_nu) was chosen on the
calibration half; docs/inpainting_methods.md has the table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
import inpaint_generalise as ig  # noqa: E402

import clpde  # noqa: E402
from tests.cases import inpaint_corpus as corpus  # noqa: E402

RULES = {
    "one nu": None,
    "nu 0.5": "flat",
    "r0 3, p 1": (3, 1),
    "r0 3, p 2": (3, 2),
    "r0 2, p 2": (2, 2),
    "r0 4, p 2": (4, 2),
}


def nu_of(rule, r: float) -> dict:
    if rule is None:
        return {"nu": 0.05}
    if rule == "flat":
        return {"nu": 0.5}
    return {"nu": 0.05 * max(1.0, r / rule[0]) ** rule[1]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--half", default="calibration", choices=("calibration", "test"))
    args = ap.parse_args()
    from clpde.inpainting import navier_stokes

    saved = navier_stokes.scaled_nu
    navier_stokes.scaled_nu = lambda nu, omega: float(nu)  # the rule is set per case here
    rows = []
    try:
        for case in corpus.build(False):
            if case.half != args.half:
                continue
            image = case.damaged()
            r = float(ndimage.distance_transform_edt(case.mask).max())
            for name, rule in RULES.items():
                start = time.perf_counter()
                out = clpde.inpaint(
                    image,
                    case.mask,
                    channel_axis=case.channel_axis,
                    progress=False,
                    method="navier-stokes",
                    **nu_of(rule, r),
                )
                rows.append(ig.score(case, out, name, time.perf_counter() - start))
            print(case.name, flush=True)
    finally:
        navier_stokes.scaled_nu = saved
    classes = sorted({r["damage"] for r in rows}, key=[r["damage"] for r in rows].index)
    print(f"{'rule':12s}" + "".join(f"{c:>12s}" for c in classes))
    for name in RULES:
        means = [
            np.mean([r["psnr"] for r in rows if r["damage"] == c and r["method"] == name])
            for c in classes
        ]
        print(f"{name:12s}" + "".join(f"{m:12.2f}" for m in means))


if __name__ == "__main__":
    main()
