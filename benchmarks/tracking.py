"""Morphing active contours against scikit-image's morphological snakes, in one run.

    python benchmarks/tracking.py [--json PATH] [--quick]

Every method starts from the true mask of frame 0 and carries it through the sequence;
the skimage baselines are propagated the same way, each frame seeded with the previous
frame's result: morphological_chan_vese (MCV) and morphological_geodesic_active_contour
(MGAC, on inverse_gaussian_gradient). "static" just keeps the first mask (how much the
object moves). Scores over frames 1..T-1, DAVIS definitions: J = region IoU; F = boundary
F-measure with a match tolerance of ceil(0.008 * image diagonal) pixels.

Sequences: the synthetic ones of tests/test_track.py (64x64, noisy, with ground truth) and
consecutive axial slices of the MNI152 2009a template that ships in nilearn's wheel, with
the white matter (its tissue probability map > 0.5) as the labelled object
(pip install nilearn nibabel; loads offline). Per-frame time is wall time per frame after
a warm-up (kernel builds excluded), everything included (pre-processing, transfers).
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
    from tests.test_track import synthetic_sequence

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

def run_clpde(frames, first):
    import clpde

    return clpde.track(frames, first, progress=False)


def _scaled(frames):
    f = frames.astype(np.float64)
    return (f - f.min()) / max(f.max() - f.min(), 1e-12)


def run_mcv(frames, first, iterations=20):
    from skimage.segmentation import morphological_chan_vese

    f = _scaled(frames)
    out = [first]
    for k in range(1, len(f)):
        out.append(morphological_chan_vese(f[k], iterations, init_level_set=out[-1],
                                           smoothing=1).astype(bool))
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
        out.append(morphological_geodesic_active_contour(
            edges, iterations, init_level_set=out[-1], smoothing=1, balloon=0).astype(bool))
    return np.array(out)


def run_static(frames, first):
    return np.repeat(first[np.newaxis], len(frames), axis=0)


def reinit_accuracy():
    """Reinitialisation of distorted circle level sets, with and without the subcell fix:
    mean |u - exact distance| in the band |d| < 3 and the largest front displacement."""
    from clpde.levelset import LevelSet
    from clpde.runtime import get_runtime

    rows = []
    for n in (64, 128):
        y, x = np.mgrid[:n, :n]
        r = 0.27 * n
        true = np.hypot(x - n / 2 + 0.4, y - n / 2 + 0.3) - r
        band = np.abs(true) < 3
        cases = {"stretched": true * (1 + x / n) * 2.5,
                 "bumpy": true * (1.5 + np.sin(x / 3.0) * np.cos(y / 4.0))}
        for name, u0 in cases.items():
            row = {"n": n, "case": name}
            for fix in (True, False):
                ls = LevelSet(get_runtime(), u0)
                ls.reinitialise(40, subcell_fix=fix)
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


METHODS = {"clpde": run_clpde, "skimage MCV": run_mcv, "skimage MGAC": run_mgac,
           "static": run_static}


def evaluate(frames, truth, repeats=1):
    """Scores of each method and its best time over `repeats` runs, the methods taking
    turns so that a busy machine slows them alike."""
    times = {name: math.inf for name in METHODS}
    masks = {}
    for _ in range(repeats):
        for name, method in METHODS.items():
            start = time.perf_counter()
            masks[name] = method(frames, truth[0])
            times[name] = min(times[name], time.perf_counter() - start)
    rows = {}
    for name in METHODS:
        j = [jaccard(m, t) for m, t in zip(masks[name][1:], truth[1:])]
        f = [boundary_f(m, t) for m, t in zip(masks[name][1:], truth[1:])]
        rows[name] = {"J": float(np.mean(j)), "F": float(np.mean(f)), "J_last": float(j[-1]),
                      "ms_per_frame": 1000 * times[name] / (len(frames) - 1)}
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=RESULTS)
    parser.add_argument("--quick", action="store_true", help="fewer frames, one timing run")
    args = parser.parse_args(argv)
    import clpde
    from clpde.runtime import get_runtime

    frames_n = 5 if args.quick else 8
    repeats = 1 if args.quick else 3
    sequences = {f"synthetic {k}": synthetic(k, frames_n)
                 for k in ("translate", "deform", "split", "merge", "phantom")}
    sequences["MNI152 white matter, axial z=90.."] = mni_slices(90, 3 if args.quick else 10)
    sequences["MNI152 white matter, axial z=60.."] = mni_slices(60, 3 if args.quick else 10)
    warm_frames, warm_truth = sequences["synthetic translate"]
    clpde.track(warm_frames[:2], warm_truth[0])  # warm-up: build the kernels
    device = get_runtime().device.name.strip()
    results = {"device": device, "sequences": {}}
    print(f"device: {device}")
    header = f"{'sequence':38s} {'method':13s} {'J':>6s} {'F':>6s} {'J last':>7s} {'ms/frame':>9s}"
    print(header)
    print("-" * len(header))
    for name, (frames, truth) in sequences.items():
        rows = evaluate(frames, truth, repeats)
        results["sequences"][name] = {"shape": list(frames.shape), **rows}
        for method, r in rows.items():
            print(f"{name:38s} {method:13s} {r['J']:6.3f} {r['F']:6.3f} {r['J_last']:7.3f} "
                  f"{r['ms_per_frame']:9.1f}")
    real = [v for k, v in results["sequences"].items() if k.startswith("MNI")]
    summary = {m: {"J": float(np.mean([r[m]["J"] for r in real])),
                   "F": float(np.mean([r[m]["F"] for r in real])),
                   "ms_per_frame": float(np.mean([r[m]["ms_per_frame"] for r in real]))}
               for m in METHODS}
    results["real_slices_mean"] = summary
    print("\nreal slices, mean:", ", ".join(
        f"{m}: J {s['J']:.3f} F {s['F']:.3f} {s['ms_per_frame']:.1f} ms" for m, s in summary.items()))
    results["reinitialisation"] = reinit_accuracy()
    print("\nreinitialisation (40 steps): mean |u - d| in the band, largest front shift (px)")
    for r in results["reinitialisation"]:
        print(f"  {r['n']:4d}^2 {r['case']:10s} Russo-Smereka {r['subcell_band_error']:.4f} "
              f"{r['subcell_front_shift']:.3f}   plain {r['plain_band_error']:.4f} "
              f"{r['plain_front_shift']:.3f}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=2))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
