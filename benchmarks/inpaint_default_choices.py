"""What the default (method "pick") fills each class's holes with: the share of the hole's
pixels that each route takes, per class and half of tests/cases/inpaint_corpus.py's corpus.

    PYTHONPATH=. python benchmarks/inpaint_default_choices.py [--half test|calibration|both]

The routes (clpde/inpainting/pick.py's docstring): the exemplar where a cluster's surround
repeats, the biharmonic fill ("smooth") where it varies smoothly or is a smooth Gaussian
field, the harmonic fill where it is a rough Gaussian field (clpde/inpainting/fields.py),
the spectral fill everywhere else. The decisions are read from the default's own calls:
pick's three tests are wrapped to record the pixels they route, so the shares are those of
the runs the corpus benchmark times (benchmarks/inpaint_generalise.py), box by box.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
import clpde  # noqa: E402
from clpde.inpainting import pick  # noqa: E402
from tests.cases import inpaint_corpus as corpus  # noqa: E402

ROUTED = {"exemplar": 0, "smooth": 0, "harmonic": 0}
GAUSS = [np.zeros(0, int)]  # the last box's Gaussian-field clusters (the smooth route skips them)


def _recording():
    """pick's three route tests, wrapped to count the hole pixels each sends away."""
    periodic, smooth, gaussian = pick.periodic_clusters, pick.smooth_clusters, pick._gaussian_route

    def periodic_clusters(*args, **kwargs):
        out = periodic(*args, **kwargs)
        ROUTED["exemplar"] += int(out.sum())
        return out

    def smooth_clusters(data, omega, parts, *rest, **kwargs):
        labels = smooth(data, omega, parts, *rest, **kwargs)
        taken = np.setdiff1d(labels, GAUSS[0])
        ROUTED["smooth"] += int((np.isin(parts[0], taken) & np.asarray(omega, bool)).sum())
        return labels

    def gaussian_route(data, omega, parts, *rest, **kwargs):
        out = gaussian(data, omega, parts, *rest, **kwargs)
        GAUSS[0] = out[1]
        hole = np.asarray(omega, bool)
        ROUTED["smooth"] += int((np.isin(parts[0], out[2]) & hole).sum())
        ROUTED["harmonic"] += int((np.isin(parts[0], np.setdiff1d(out[1], out[2])) & hole).sum())
        return out

    pick.periodic_clusters, pick.smooth_clusters = periodic_clusters, smooth_clusters
    pick._gaussian_route = gaussian_route


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--half", choices=("test", "calibration", "both"), default="both")
    args = parser.parse_args(argv)
    halves = ("test", "calibration") if args.half == "both" else (args.half,)
    _recording()
    shares = {}  # (class, half) -> [hole px, exemplar px, smooth px, cases routed, cases,
    # harmonic px]
    for case in corpus.build():
        if case.half not in halves:
            continue
        ROUTED.update(exemplar=0, smooth=0, harmonic=0)
        GAUSS[0] = np.zeros(0, int)
        clpde.inpaint(case.damaged(), case.mask, channel_axis=case.channel_axis)
        s = shares.setdefault((case.damage, case.half), [0, 0, 0, 0, 0, 0])
        s[0] += int(case.mask.sum())
        s[1] += ROUTED["exemplar"]
        s[2] += ROUTED["smooth"]
        s[3] += any(ROUTED.values())
        s[4] += 1
        s[5] += ROUTED["harmonic"]
    print("share of the hole's pixels per route (" + " / ".join(halves) + ")")
    head = ("spectral", "smooth", "harmonic", "exemplar", "cases routed")
    print(f"{'class':11s} " + " ".join(f"{h:>15s}" for h in head))
    for d in corpus.CLASSES:
        cells = [shares.get((d, h)) for h in halves]
        if not any(cells):
            continue

        def col(k, cells=cells):
            return " / ".join("-" if c is None else f"{c[k] / max(c[0], 1):.2f}" for c in cells)

        spectral = " / ".join(
            "-" if c is None else f"{1 - (c[1] + c[2] + c[5]) / max(c[0], 1):.2f}" for c in cells
        )
        routed = " / ".join("-" if c is None else f"{c[3]}/{c[4]}" for c in cells)
        print(f"{d:11s} {spectral:>15s} {col(2):>15s} {col(5):>15s} {col(1):>15s} {routed:>15s}")


if __name__ == "__main__":
    main()
