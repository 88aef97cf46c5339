"""method="spectral" solved in boxes around the damage (its MARGIN) against one call on the
whole image (`boxes=False`, which is how every spectral call ran before it had a margin):
where the results differ, by how much, and the time and host memory of a small hole in a
large image.

    python benchmarks/inpaint_spectral_boxes.py [--quick] [--big 4000] [--no-corpus] [--json PATH]

Quality: the damaged astronaut (clpde.data.damaged_astronaut, 512x512 colour) and every case
of tests/cases/inpaint_corpus.py (both halves, 128x128; nothing is chosen from them here: the
margin is the method's reach, not a fitted value). A box holding one hole gives the whole
image's fill bit for bit; where a box holds a cluster of holes, the block grid starts at the
cluster's corner instead of the whole damage's, and colour is decorrelated by the box's own
principal axes, so the fills differ. PSNR is inside the mask (corpus peaks: 255, 65535, the
truth's range for float data).

Memory: a `--big` x `--big` uint8 colour image with two small holes far apart; the peak of
the host's allocations (tracemalloc, which sees numpy's buffers) during one warm call, with
and without boxes, beside the image's own size. Time: wall time of that call, and of a call
on 300 specks of dust spread over the image (a box each where they lie apart).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))


def _psnr(truth, result, mask, peak) -> float:
    d = np.asarray(result, np.float64)[mask] - np.asarray(truth, np.float64)[mask]
    mse = max(float(np.mean(d**2)), peak**2 * 1e-8)  # 80 dB for an exact fill
    return float(10 * np.log10(peak**2 / mse))


def _both(image, mask, axis):
    """(whole-image result, boxed result, boxes, seconds whole, seconds boxed)."""
    import clpde

    t0 = time.perf_counter()
    whole = clpde.inpaint(image, mask, channel_axis=axis, method="spectral", boxes=False)
    t1 = time.perf_counter()
    boxed, info = clpde.inpaint(image, mask, channel_axis=axis, method="spectral", return_info=True)
    t2 = time.perf_counter()
    return whole, boxed, len(info.boxes), t1 - t0, t2 - t1


def quality(quick: bool) -> list[dict]:
    from clpde.data import damaged_astronaut
    from tests.cases import inpaint_corpus as corpus

    rows = []
    original, damaged, mask = damaged_astronaut()
    cases = [("astronaut-512/damaged", "calibration", original, damaged, mask, 255.0, -1)]
    for case in corpus.build(quick=quick):
        cases.append(
            (
                case.name,
                case.half,
                case.truth,
                case.damaged(),
                case.mask,
                case.peak,
                case.channel_axis,
            )
        )
    for name, half, truth, image, mask, peak, axis in cases:
        whole, boxed, nboxes, t_whole, t_boxed = _both(image, mask, axis)
        same = whole.dtype == boxed.dtype and whole.tobytes() == boxed.tobytes()
        diff = np.abs(whole.astype(np.float64) - boxed.astype(np.float64))
        rows.append(
            {
                "case": name,
                "half": half,
                "boxes": nboxes,
                "identical": bool(same),
                "max_abs_diff": float(diff.max()) / peak,
                "psnr_whole": _psnr(truth, whole, mask, peak),
                "psnr_boxed": _psnr(truth, boxed, mask, peak),
                "seconds_whole": t_whole,
                "seconds_boxed": t_boxed,
            }
        )
        r = rows[-1]
        print(
            f"{name:36s} boxes {nboxes:3d}  identical {str(same):5s}  "
            f"PSNR whole {r['psnr_whole']:6.2f}  boxed {r['psnr_boxed']:6.2f}  "
            f"({r['psnr_boxed'] - r['psnr_whole']:+.3f} dB)  "
            f"{t_whole:5.2f} s / {t_boxed:5.2f} s",
            flush=True,
        )
    return rows


def summary(rows: list[dict]) -> dict:
    by_class: dict[str, list] = {}
    for r in rows:
        by_class.setdefault(r["case"].split("/")[-1], []).append(r)
    out = {}
    print("\nper damage class: cases, identical, mean PSNR whole / boxed (dB), difference")
    for name, rs in sorted(by_class.items()):
        w = float(np.mean([r["psnr_whole"] for r in rs]))
        b = float(np.mean([r["psnr_boxed"] for r in rs]))
        same = sum(r["identical"] for r in rs)
        out[name] = {"cases": len(rs), "identical": same, "psnr_whole": w, "psnr_boxed": b}
        print(f"  {name:12s} {len(rs):3d} {same:3d}  {w:6.2f} / {b:6.2f}  {b - w:+.3f}")
    diffs = [r["psnr_boxed"] - r["psnr_whole"] for r in rows]
    out["all"] = {
        "cases": len(rows),
        "identical": sum(r["identical"] for r in rows),
        "mean_difference_db": float(np.mean(diffs)),
        "min_difference_db": float(np.min(diffs)),
        "max_difference_db": float(np.max(diffs)),
        "seconds_whole": float(sum(r["seconds_whole"] for r in rows)),
        "seconds_boxed": float(sum(r["seconds_boxed"] for r in rows)),
    }
    a = out["all"]
    print(
        f"  all: {a['cases']} cases, {a['identical']} identical; boxed - whole "
        f"mean {a['mean_difference_db']:+.3f} dB (from {a['min_difference_db']:+.3f} to "
        f"{a['max_difference_db']:+.3f}); time {a['seconds_whole']:.1f} s whole, "
        f"{a['seconds_boxed']:.1f} s boxed"
    )
    return out


def big(size: int) -> dict:
    import clpde
    from clpde.data import damaged_astronaut

    original = damaged_astronaut()[0]
    reps = -(-size // original.shape[0])
    image = np.tile(original, (reps, reps, 1))[:size, :size].copy()
    mask = np.zeros(image.shape[:2], bool)
    mask[size // 3 : size // 3 + 24, size // 3 : size // 3 + 40] = True
    mask[2 * size // 3 : 2 * size // 3 + 6, 2 * size // 3 : 2 * size // 3 + 60] = True
    warm = np.zeros((64, 64), bool)  # a warm-up call: no program build is counted
    warm[30:34, 20:40] = True
    clpde.inpaint(image[:64, :64], warm, channel_axis=-1, method="spectral")
    out = {"size": size, "image_mib": image.nbytes / 2**20}
    results = {}
    for label, boxes in (("whole", False), ("boxed", True)):
        tracemalloc.start()
        t0 = time.perf_counter()
        results[label] = clpde.inpaint(image, mask, channel_axis=-1, method="spectral", boxes=boxes)
        seconds = time.perf_counter() - t0
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        out[label] = {"seconds": seconds, "peak_mib": peak / 2**20}
        print(
            f"{size}x{size} colour, two small holes, {label:5s}: {seconds:6.2f} s, "
            f"host peak {peak / 2**20:8.1f} MiB (the image: {out['image_mib']:.1f} MiB)",
            flush=True,
        )
    out["identical"] = results["whole"].tobytes() == results["boxed"].tobytes()
    print(f"  whole and boxed identical: {out['identical']}")
    # Many small holes: a box each where they lie apart, so many calls and launches instead
    # of one call's few; what that costs against converting the whole image.
    rng = np.random.default_rng(0)
    dust = np.zeros(image.shape[:2], bool)
    for _ in range(300):
        y, x = rng.integers(0, size - 4, 2)
        r = int(rng.integers(1, 5))
        dust[y : y + r, x : x + r] = True
    for label, boxes in (("dust_whole", False), ("dust_boxed", True)):
        t0 = time.perf_counter()
        _, info = clpde.inpaint(
            image, dust, channel_axis=-1, method="spectral", boxes=boxes, return_info=True
        )
        seconds = time.perf_counter() - t0
        out[label] = {"seconds": seconds, "boxes": len(info.boxes)}
        print(
            f"{size}x{size} colour, 300 specks, {label}: {len(info.boxes)} boxes, {seconds:.2f} s"
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one corpus case per class and half")
    parser.add_argument("--big", type=int, default=4000, help="side of the large image (0: skip)")
    parser.add_argument("--json", default=None, help="write the results here")
    parser.add_argument("--no-corpus", action="store_true", help="the large image only")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    report = {}
    if args.big:
        report["big"] = big(args.big)
    if not args.no_corpus:
        rows = quality(args.quick)
        report["cases"] = rows
        report["summary"] = summary(rows)
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
