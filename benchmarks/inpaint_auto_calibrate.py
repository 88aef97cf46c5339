"""Calibration of method="auto"'s choice between the structure method and the exemplar.

    python benchmarks/inpaint_auto_calibrate.py [--json PATH] [--classes text,thick,...]
                                                [--methods M,...] [--rule]

Runs every case of benchmarks/inpaint_quality.py (text, scratches and blobs over seven
photos, the structure class, thick holes, and the texture, periodic and thick-hole cases of
inpaint_texture_cases.py) with the structure method (coherence), the exemplar, the exemplar
with a structure guide, clpde's auto, and the peers (OpenCV NS and Telea, scikit-image's
biharmonic). clpde.inpaint splits the mask into boxes (clpde/inpainting/boxes.py, with
the structure method's margin); for each box it records the features that auto measures
(clpde/inpainting/choose.py: the hole's radius and the texture around it) and each method's
squared error over the box's hole pixels. Then:

- the table, per case, of each method's PSNR, SSIM (inside the mask) and edge energy, and
  the methods auto picked in its boxes;
- with --rule, for a grid of thresholds, the mean PSNR per class of the composite that
  picks per box by choose.pick's rule (the calibration: the thresholds must hold on every
  class, not on one picture).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import inpaint_quality as q  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "inpaint_auto_calibrate.json"


def clpde_run(**options):
    def run(image, mask):
        import clpde

        axis = -1 if image.ndim == 3 else None
        return clpde.inpaint(image, mask, channel_axis=axis, progress=False, seed=0,
                             return_info=True, **options)
    return run


def methods():
    import cv2

    return {
        "coherence": clpde_run(method="coherence"),
        "exemplar": clpde_run(method="exemplar"),  # its structure guide automatic
        "exemplar-plain": clpde_run(method="exemplar", structure=0.0),
        "exemplar-structure": clpde_run(method="exemplar", structure=1.0),
        "auto": clpde_run(method="auto"),
        "opencv-ns": lambda im, m: q.run_cv2(im, m, cv2.INPAINT_NS),
        "opencv-telea": lambda im, m: q.run_cv2(im, m, cv2.INPAINT_TELEA),
        "skimage-biharmonic": q.run_biharmonic,
    }


def box_features(image, mask):
    """[(box, features)] for clpde.inpaint's boxes of this mask under the structure method."""
    from clpde.inpainting import boxes, choose
    from clpde.inpainting import registry as inpainting

    module = inpainting.load("coherence")
    data = image.astype(np.float64) / 255.0
    data = data[None] if data.ndim == 2 else np.moveaxis(data, -1, 0)
    out = []
    for y0, y1, x0, x1 in boxes.boxes(mask, lambda crop: inpainting.margin(module, crop, {})):
        out.append(((y0, y1, x0, x1), choose.features(data[:, y0:y1, x0:x1], mask[y0:y1, x0:x1])))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, default=RESULTS)
    ap.add_argument("--classes", default="", help="comma-separated classes to run")
    ap.add_argument("--methods", default="", help="comma-separated methods to run")
    ap.add_argument("--rule", action="store_true", help="evaluate a grid of thresholds")
    args = ap.parse_args(argv)
    table = methods()
    if args.methods:
        table = {k: v for k, v in table.items() if k in args.methods.split(",")}
    clpde_run(method="exemplar")(np.zeros((64, 64, 3), np.uint8), np.eye(64, dtype=bool))
    rows, boxes_rows = [], []
    for kind, name, image, mask in q.cases():
        if args.classes and kind not in args.classes.split(","):
            continue
        feats = box_features(image, mask)
        results = {}
        for method, fn in table.items():
            t0, c0 = time.perf_counter(), time.process_time()
            out = fn(image, mask)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            info = None
            if isinstance(out, tuple):
                out, info = out
            results[method] = out
            row = {"class": kind, "case": name, "method": method, "seconds": wall, "cpu": cpu,
                   "psnr": q.psnr_in_mask(out, image, mask),
                   "ssim": q.ssim_in_mask(out, image, mask),
                   "edge_energy": q.edge_energy(out, image, mask)}
            if method == "auto" and info is not None:
                row["picked"] = sorted(set(getattr(info, "box_methods", []) or [info.method]))
            rows.append(row)
            print(f"{kind:16s} {name:22s} {method:20s} PSNR {row['psnr']:6.2f} SSIM "
                  f"{row['ssim']:.3f} E {row['edge_energy']:.2f} {cpu:6.2f} s CPU "
                  f"{row.get('picked', '')}", file=sys.stderr, flush=True)
        for box, f in feats:
            y0, y1, x0, x1 = box
            m = mask[y0:y1, x0:x1]
            sse = {meth: float(((res[y0:y1, x0:x1][m].astype(np.float64)
                                 - image[y0:y1, x0:x1][m]) ** 2).sum())
                   for meth, res in results.items()}
            boxes_rows.append({"class": kind, "case": name, "box": box,
                               "n": int(m.sum()) * (1 if image.ndim == 2 else image.shape[2]),
                               **f, "sse": sse})
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"rows": rows, "boxes": boxes_rows}, indent=1))
    print_table(rows)
    if args.rule:
        rule_grid(boxes_rows)


def print_table(rows):
    names = list(dict.fromkeys(r["method"] for r in rows))
    print("| class | case | " + " | ".join(names) + " | auto picked |")
    print("|---|---|" + "---|" * len(names) + "---|")
    cases = list(dict.fromkeys((r["class"], r["case"]) for r in rows))
    for kind, case in cases:
        rs = {r["method"]: r for r in rows if r["class"] == kind and r["case"] == case}
        cells = [f"{rs[n]['psnr']:.2f} / {rs[n]['ssim']:.3f} / {rs[n]['edge_energy']:.2f}"
                 if n in rs else "" for n in names]
        picked = ", ".join(rs.get("auto", {}).get("picked", []))
        print(f"| {kind} | {case} | " + " | ".join(cells) + f" | {picked} |")
    print("\nMeans per class (PSNR capped at 60 dB / SSIM / edge energy / CPU s):")
    print("| class | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for kind in dict.fromkeys(r["class"] for r in rows):
        cells = []
        for n in names:
            rs = [r for r in rows if r["class"] == kind and r["method"] == n]
            cells.append(f"{np.mean([min(r['psnr'], 60) for r in rs]):.2f} / "
                         f"{np.mean([r['ssim'] for r in rs]):.3f} / "
                         f"{np.mean([r['edge_energy'] for r in rs]):.2f} / "
                         f"{np.mean([r['cpu'] for r in rs]):.2f}")
        print(f"| {kind} | " + " | ".join(cells) + " |")


def rule_grid(boxes_rows):
    """Mean PSNR per class of the per-box composite of choose.pick's rule, for a grid of
    its thresholds (each box takes the squared error of the method the rule names)."""
    classes = list(dict.fromkeys(b["class"] for b in boxes_rows))

    def rule(b, radius, texture, periodic):
        if b["periodicity"] >= periodic:
            return "exemplar-plain"
        return "exemplar-structure" if b["radius"] >= radius and b["texture"] >= texture \
            else "coherence"

    print("\nPer-box composite of the rule, mean PSNR per class (R: MIN_RADIUS, T: "
          "MIN_TEXTURE, P: MIN_PERIODICITY):")
    print("| R | T | P | " + " | ".join(classes) + " |")
    print("|---|---|---|" + "---|" * len(classes))
    grid = [(6, t, 0.9) for t in (0, 0.002, 0.005, 0.008, 0.01, 0.02, 0.04)]
    grid += [(r, 0.005, 0.9) for r in (0, 4, 5, 8, 12)]
    grid += [(6, 0.005, p) for p in (0.8, 0.85, 0.95, 1.01)]
    for radius, texture, periodic in grid:
        means = []
        for kind in classes:
            psnrs = []
            for case in dict.fromkeys(b["case"] for b in boxes_rows if b["class"] == kind):
                bs = [b for b in boxes_rows if b["class"] == kind and b["case"] == case]
                sse = sum(b["sse"][rule(b, radius, texture, periodic)] for b in bs)
                n = sum(b["n"] for b in bs)
                psnrs.append(min(60.0, 10 * np.log10(255.0 ** 2 / max(sse / n, 1e-12))))
            means.append(f"{np.mean(psnrs):.2f}")
        print(f"| {radius} | {texture} | {periodic} | " + " | ".join(means) + " |")


if __name__ == "__main__":
    main()
