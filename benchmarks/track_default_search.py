"""One default for video and slices: candidate configurations of clpde.track on the synthetic
corpus's calibration half (mean of the class means of the IoU per frame) and on the named
real sequences (carphone's hand-drawn frames, the MNI152 white-matter slices z = 90..99 and
60..69), in one run, each candidate against the current default.

    python benchmarks/track_default_search.py                 # every candidate
    python benchmarks/track_default_search.py --only kalman+adaptive

A candidate is chosen only on these: the calibration half, the real sequences' rule (no
more than a small margin below the current default on each) and the earlier default's hard
cases (a shadow, a flicker, a distractor: every frame above 0.9, as
tests/tracking/test_track.py checks). The test half is reported
afterwards by benchmarks/tracking_generalise.py, never read here.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from track_corpus import corpus  # noqa: E402
from tracking import carphone, jaccard, mni_slices  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"

# Every candidate spelled out in full, so the table keeps its meaning when the defaults change.
CURRENT = {"motion": "kalman", "discrepancy": "ncc"}  # the default before this search
NO_TERMS = {"motion": "kalman", "discrepancy": "adaptive", "region_weight": 0.0, "curvature": 0.0}
CN = "clpde.tracking.morph:CONTRAST_NOISE"  # the adaptive weight's noise factor
LIGHT = "clpde.tracking.tracker:LIGHT_CHANGE"  # the light gate's threshold
QUIET = "clpde.tracking.tracker:QUIET_FACTOR"  # the noise factor's rise below it
CANDIDATES = {
    "kalman+ncc (the default before)": CURRENT,
    "adaptive option (components+adaptive, region 1, curvature 0.3)": {
        "motion": "components",
        "discrepancy": "adaptive",
        "region_weight": 1.0,
        "curvature": 0.3,
    },
    "kalman+adaptive, region 1, curvature 0.3": {
        **NO_TERMS,
        "region_weight": 1.0,
        "curvature": 0.3,
    },
    "kalman+adaptive, region 0.1": {**NO_TERMS, "region_weight": 0.1, "max_iterations": 40},
    "kalman+adaptive, region 0.25": {**NO_TERMS, "region_weight": 0.25, "max_iterations": 40},
    "kalman+adaptive, curvature 0.05": {**NO_TERMS, "curvature": 0.05, "max_iterations": 40},
    **{
        f"kalman+adaptive, no terms, noise factor {cn}, no light gate": {
            **NO_TERMS,
            "_patch": {CN: float(cn), QUIET: 1.0},
        }
        for cn in (1, 4, 16, 64, 128, 256, 1024)
    },
    **{
        f"kalman+adaptive, no terms, light gate: change {change}, quiet factor {quiet}": {
            **NO_TERMS,
            "_patch": {LIGHT: change, QUIET: float(quiet)},
        }
        for change, quiet in (
            (3.0, 4),
            (4.5, 4),
            (6.0, 4),
            (3.0, 16),
            (4.5, 16),
            (6.0, 16),
            (6.0, 32),
            (3.0, 64),
            (4.5, 64),
            (6.0, 64),
            (8.0, 64),
            (4.5, 128),
            (6.0, 128),
            (6.0, 256),
        )
    },
    "the default (kalman+adaptive, no terms, light gate 6.0 / 32)": {},
    "the default, 20 it.": {"max_iterations": 20},
    "the default, 60 it.": {"max_iterations": 60},
    "the default with motion components": {"motion": "components"},
}


def run(frames, first, options):
    """clpde.track with `options`; '_patch': {'module:NAME': value} sets module constants
    for the run (e.g. a weight chosen on the calibration half), '_region': RegionTerm's
    keyword arguments."""
    import functools
    import importlib

    import clpde
    from clpde.tracking import tracker

    options = dict(options)
    saved = []
    for key, value in options.pop("_patch", {}).items():
        module, name = key.split(":")
        mod = importlib.import_module(module)
        saved.append((mod, name, getattr(mod, name)))
        setattr(mod, name, value)
    region = options.pop("_region", None)
    if region:
        saved.append((tracker, "RegionTerm", tracker.RegionTerm))
        tracker.RegionTerm = functools.partial(tracker.RegionTerm, **region)
    try:
        return clpde.track(frames, first, progress=False, **options)
    finally:
        for mod, name, value in reversed(saved):
            setattr(mod, name, value)


def calibration_mean(options, data):
    per = {}
    for frames, truth, cls in data.values():
        masks = run(frames, truth[0], options)
        per.setdefault(cls, []).extend(
            jaccard(a, b) for a, b in zip(masks[1:], truth[1:], strict=True)
        )
    means = {c: float(np.mean(v)) for c, v in per.items()}
    return float(np.mean(list(means.values()))), means


def real_j(options, real):
    out = {}
    for name, (frames, truth) in real.items():
        masks = run(frames, truth[0], options)
        out[name] = float(np.mean([jaccard(masks[k], truth[k]) for k in sorted(truth) if k > 0]))
    return out


def hard_min(options):
    """The worst frame's IoU on the earlier default's hard cases (tests/tracking/test_track.py:
    a shadow, a flicker, a distractor; 8 frames each), which it must keep above 0.9."""
    from tests.tracking.test_track import synthetic_sequence

    worst = {}
    for kind in ("shadow", "flicker", "distractor"):
        frames, truth = synthetic_sequence(kind, frames=8)
        masks = run(frames, truth[0], options)
        worst[kind] = float(min(jaccard(m, t) for m, t in zip(masks, truth, strict=True)))
    return worst


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=None, metavar="SUBSTRING")
    parser.add_argument("--json", type=Path, default=RESULTS / "track_default_search.json")
    parser.add_argument("--no-corpus", action="store_true", help="the real sequences only")
    parser.add_argument(
        "--config",
        nargs=2,
        action="append",
        default=[],
        metavar=("NAME", "JSON"),
        help="an extra candidate: a name and its options as JSON",
    )
    args = parser.parse_args(argv)
    for name, text in args.config:
        CANDIDATES[name] = json.loads(text)
    names = [n for n in CANDIDATES if not args.only or any(o in n for o in args.only)]
    data = None if args.no_corpus else corpus("calibration")
    f, truth = carphone()
    real = {"carphone": (f, truth)}
    for z in (90, 60):
        frames, masks = mni_slices(z, 10)
        real[f"MNI z={z}"] = (frames, dict(enumerate(masks)))
    rows = json.loads(args.json.read_text()) if args.json.exists() else {}
    for name in names:
        t0 = time.perf_counter()
        row = {"options": CANDIDATES[name]}
        if data is not None:
            row["calibration"], row["per_class"] = calibration_mean(CANDIDATES[name], data)
        row.update(real_j(CANDIDATES[name], real))
        row["hard"] = hard_min(CANDIDATES[name])
        row["seconds"] = time.perf_counter() - t0
        rows[name] = row
        print(
            f"{name}: calibration {row.get('calibration', float('nan')):.3f}  "
            + "  ".join(f"{k} {row[k]:.3f}" for k in real)
            + "  hard "
            + "/".join(f"{v:.2f}" for v in row["hard"].values())
            + f"  ({row['seconds']:.0f} s)  "
            + " ".join(f"{c}:{v:.2f}" for c, v in row.get("per_class", {}).items()),
            flush=True,
        )
        RESULTS.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
