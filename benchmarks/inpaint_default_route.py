"""A default that picks per cluster of damage by cheap evidence at the hole: would it gain?
From the fills cached by benchmarks/inpaint_vote_cache.py (no filling here), each cluster's
measures of its surround and each candidate's squared error there; a rule then picks, per
cluster, spectral (the default), a smooth fill (biharmonic) or the exemplar, and the case
is scored as if the picked fills had been run.

    python benchmarks/inpaint_vote_cache.py --half both --masks hole   # first: the fills
    python benchmarks/inpaint_default_route.py [--half calibration|test|both]

Measures per cluster (a component of the hole grown by 1 px; clpde/inpainting/choose.py's
detail image: grey minus its local mean over the known pixels):

- radius: its half-thickness (px);
- texture: RMS of the detail on the known pixels within 8 px of it;
- periodicity: the largest autocorrelation of the detail (choose.LAGS) in a window of the
  cluster's bounding box grown by WINDOW px (only for clusters at least 3 px thick).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from inpaint_vote_sound import load  # noqa: E402

from tests.cases import inpaint_corpus as corpus  # noqa: E402

WINDOW = 24
OPTIONS = ("spectral", "biharmonic", "exemplar")


def measures(c):
    """Per cluster (label 1..count): radius, texture, periodicity (arrays)."""
    from clpde.inpainting import choose

    known = ~c.omega
    detail, ok = choose._detail(c.data, known)
    ring = known & (c.dist <= 8)
    lab = np.arange(1, c.count + 1)
    sq = ndimage.mean(detail.astype(float) ** 2, np.where(ring, c.owner, 0), lab)
    texture = np.sqrt(np.nan_to_num(np.asarray(sq, float)))
    period = np.zeros(c.count)
    slices = ndimage.find_objects(c.clusters)
    for k, s in enumerate(slices):
        if s is None or c.radius[k] < 3:
            continue
        y0, y1 = max(s[0].start - WINDOW, 0), s[0].stop + WINDOW
        x0, x1 = max(s[1].start - WINDOW, 0), s[1].stop + WINDOW
        period[k] = choose._periodicity(detail[y0:y1, x0:x1], ok[y0:y1, x0:x1])
    return np.asarray(c.radius, float), texture, period


def outputs(c):
    """{candidate: the case's output image} (bounds applied, as clpde.inpaint writes)."""
    out = {}
    for k, n in enumerate(c.names):
        filled = c.data.copy()
        filled[:, c.omega] = c.hole[k]
        img = c.case.damaged().copy()
        c.job._write(img, c.box, filled, c.omega)
        out[n] = img
    return out


def route(radius, texture, period, rule):
    """The option index (into OPTIONS) per cluster."""
    pick = np.zeros(radius.shape, int)
    if rule.get("smooth") is not None:
        pick[texture < rule["smooth"]] = 1
    if rule.get("period") is not None:
        pick[(period >= rule["period"]) & (radius >= rule.get("min_radius", 3))] = 2
    return pick


def main(argv=None):
    from clpde.inpainting import auto

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    args = parser.parse_args(argv)
    names = auto.candidates()
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    rows = []
    for c in load(halves, names):
        radius, texture, period = measures(c)
        outs = outputs(c)
        rows.append((c, radius, texture, period, outs))
    rules = {"spectral (today)": {}}
    for p in (0.8, 0.85, 0.9, 0.95):
        rules[f"period >= {p}"] = {"period": p}
    for t in (0.002, 0.004, 0.008):
        rules[f"texture < {t}"] = {"smooth": t}
        rules[f"texture < {t}, period >= 0.9"] = {"smooth": t, "period": 0.9}
    for half in halves:
        sel = [r for r in rows if r[0].case.half == half]
        print(f"\n{half} ({len(sel)} cases): rule | mean over classes | per class")
        for label, rule in rules.items():
            by = {}
            for c, radius, texture, period, outs in sel:
                pick = route(radius, texture, period, rule)
                img = outs["spectral"].copy()
                lab = np.zeros(c.omega.shape, int)
                lab[c.omega] = c.hole_label
                for k, n in enumerate(OPTIONS):
                    m = np.isin(lab, 1 + np.flatnonzero(pick == k)) & c.omega
                    img[m] = outs[n][m]
                by.setdefault(c.case.damage, []).append(corpus.psnr(c.case, img))
            means = {d: np.mean(v) for d, v in by.items()}
            print(
                f"{label:32s} {np.mean(list(means.values())):6.2f}  "
                + " ".join(f"{d[:5]}={means[d]:.2f}" for d in corpus.CLASSES if d in means)
            )


if __name__ == "__main__":
    main()
