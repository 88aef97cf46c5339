"""Variants of structure-texture's split and of the exemplar's structure guide, mean of seeds.

    python benchmarks/inpaint_structure_variants.py --tv-weights 1,1.5,2 [--structure NAME]
    python benchmarks/inpaint_structure_variants.py --guide-kappas 25,50,100 [--classes thick]

--tv-weights: clpde.inpaint(method="structure-texture", tv_weight=w, seed=s) on every class
of inpaint_texture_cases (texture, periodic, thick), optionally with structure=NAME.
--guide-kappas: the exemplar's solve with exemplar.GUIDE_KAPPA set to each value (the
coherence kappa of the structure guide in holes deeper than exemplar.GUIDE_DEPTH; 25 is the
fill's own). Both print, per class and variant, the mean over the cases and seeds 0-2 of
PSNR in the hole (capped at 60 dB), SSIM over the holes' boxes and the edge energy
(inpaint_texture_quick.scores). docs/inpainting_texture.md has the results.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from inpaint_texture_cases import texture_cases  # noqa: E402
from inpaint_texture_quick import from_data, scores, to_data  # noqa: E402

SEEDS = (0, 1, 2)


def structure_texture(w, structure):
    import clpde

    extra = {"structure": structure} if structure else {}

    def run(image, mask, seed):
        axis = -1 if image.ndim == 3 else None
        return clpde.inpaint(
            image,
            mask,
            channel_axis=axis,
            method="structure-texture",
            tv_weight=w,
            seed=seed,
            **extra,
        )

    return run


def exemplar_with_kappa(kappa):
    from clpde.inpainting import exemplar
    from clpde.runtime import get_runtime

    def run(image, mask, seed):
        saved, exemplar.GUIDE_KAPPA = exemplar.GUIDE_KAPPA, kappa
        try:
            return from_data(exemplar.solve(to_data(image), mask, get_runtime(), seed=seed), image)
        finally:
            exemplar.GUIDE_KAPPA = saved

    return run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tv-weights", default="", help="comma-separated ROF weights")
    ap.add_argument("--structure", default="", help="structure-texture's structure method")
    ap.add_argument("--guide-kappas", default="", help="comma-separated guide kappas")
    ap.add_argument("--classes", default="texture,periodic,thick")
    args = ap.parse_args(argv)
    variants = {
        f"structure-texture tv_weight={w}"
        + (f" {args.structure}" if args.structure else ""): structure_texture(
            float(w), args.structure
        )
        for w in filter(None, args.tv_weights.split(","))
    }
    variants.update(
        {
            f"exemplar guide kappa={k}": exemplar_with_kappa(float(k))
            for k in filter(None, args.guide_kappas.split(","))
        }
    )
    if not variants:
        ap.error("give --tv-weights or --guide-kappas")
    classes = args.classes.split(",")
    means = {}
    for case in texture_cases():
        if case["class"] not in classes:
            continue
        for name, run in variants.items():
            vals = [
                [
                    min(v, 60.0)
                    for v in scores(
                        run(case["image"], case["mask"], seed), case["image"], case["mask"]
                    )
                ]
                for seed in SEEDS
            ]
            print(
                f"{case['name']:14s} {name:40s} PSNR %.2f SSIM %.3f energy %.2f"
                % tuple(np.mean(vals, 0)),
                file=sys.stderr,
                flush=True,
            )
            means.setdefault((case["class"], name), []).append(np.mean(vals, 0))
    print("| class | variant | PSNR (dB) | SSIM | edge energy |\n|---|---|---|---|---|")
    for (cls, name), rows in means.items():
        print(f"| {cls} | {name} | %.2f | %.3f | %.2f |" % tuple(np.mean(rows, 0)))


if __name__ == "__main__":
    main()
