"""Does the inpainting default generalise? Every clpde method, the default and the peers, in
one run, on both halves of tests/cases/inpaint_corpus.py's corpus.

    python benchmarks/inpaint_generalise.py [--quick] [--half test|calibration|both]
                                            [--only NAME,...] [--skip NAME,...] [--slice A:B]
                                            [--extra NAME,...] [--json PATH]
                                            [--damage CLASS,...] [--more]
                                            [--log PATH] [--from-log LOG ...]

Methods (every peer's settings fixed before any result was looked at):

- clpde: every installed method of clpde.inpainting, and the default (`clpde.inpaint(image,
  mask)`, no options);
- scikit-image's inpaint_biharmonic;
- OpenCV's INPAINT_NS and INPAINT_TELEA, radius 3;
- OpenCV contrib's FSR, fast and best, at their defaults (`cv2.xphoto.inpaint`, mask nonzero
  = known). FSR works in 8 bits: on uint16 and float data, "fsr-*" is what a user gets
  (the data quantised to 8 bits over its range, filled, mapped back, scored against the
  real truth), and "fsr-* (8-bit data)" is FSR on the 8-bit version of the same data,
  scored against the 8-bit truth, next to "default (8-bit data)", the default on that same
  8-bit version: a lead that comes from quantisation alone shows there;
- PyPI's PatchMatch (PyPatchMatch, patch size 3 as its examples; 8-bit RGB like FSR).

Per class and half: mean PSNR in the hole, mean SSIM there, the count of images where the
default beats the best peer, the worst case (the default minus the best peer, and the
case), the time, and the default's time over biharmonic's. Tables for the test half and the
calibration half side by side (test / calibration in each cell). Every clpde method is
called once on a grey and a colour image before the timed run, so the timings exclude
program builds (benchmarks/cold_build.py measures those).
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "inpaint_generalise.json"
PEERS = ("biharmonic", "opencv-ns", "opencv-telea", "fsr-fast", "fsr-best", "patchmatch")


# ---- conversions -------------------------------------------------------------------------
def to_u8(image, case):
    """The 8-bit version a user makes of non-8-bit data: its range mapped onto 0..255."""
    a = np.asarray(image, np.float64)
    lo, hi = _range(case)
    return np.clip(np.rint((a - lo) / (hi - lo) * 255), 0, 255).astype(np.uint8)


def from_u8(image, case):
    lo, hi = _range(case)
    return cast(np.asarray(image, np.float64) / 255 * (hi - lo) + lo, case.truth.dtype)


def _range(case):
    known = case.truth[~case.mask]
    return float(np.min(known)), float(np.max(known)) if np.ptp(known) else float(np.min(known)) + 1


def cast(values, dtype):
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        return np.clip(np.rint(values), info.min, info.max).astype(dtype)
    return np.asarray(values).astype(dtype)


def _rgb(u8):
    return np.ascontiguousarray(np.repeat(u8[..., None], 3, -1) if u8.ndim == 2 else u8)


# ---- methods: fn(damaged image, mask, case) -> result of the image's dtype --------------------
def clpde_method(name):
    def run(image, mask, case):
        import clpde

        kw = {} if name == "default" else {"method": name}
        out, info = clpde.inpaint(
            image,
            mask,
            channel_axis=case.channel_axis,
            progress=False,
            seed=0,
            return_info=True,
            **kw,
        )
        CHOSEN[0] = _chosen(info)
        return out

    return run


CHOSEN = [None]  # what the last clpde call filled its hole with: {method: share of pixels}


def _chosen(info):
    """{method: share of the hole's pixels} of a clpde run (auto: from its votes' weights)."""
    share = {}
    if info.choices:
        for report in info.choices:
            for choice in report["choices"]:
                for m, w in choice["weights"].items():
                    share[m] = share.get(m, 0.0) + w * choice["pixels"]
    else:
        share[info.method] = float(max(info.omega_pixels, 1))
    total = sum(share.values()) or 1.0
    return {m: v / total for m, v in share.items()}


def biharmonic(image, mask, case):
    from skimage.restoration import inpaint_biharmonic

    data = np.where(mask[..., None] if image.ndim == 3 else mask, 0, np.asarray(image, np.float64))
    return cast(inpaint_biharmonic(data, mask, channel_axis=case.channel_axis), image.dtype)


def harmonic(image, mask, case):
    """The harmonic fill (Laplacian zero) of each cluster of the hole, on the host: the fill
    pick's Gaussian route gives rough fields (clpde/inpainting/smooth.py, order 1)."""
    from clpde.inpainting import pick, smooth

    planes = np.asarray(image, np.float64)
    planes = planes[None] if planes.ndim == 2 else np.moveaxis(planes, -1, 0)
    planes = np.where(mask, 0.0, planes)
    clusters, count, _ = pick.clusters_of(mask)
    out = smooth.fill(planes, mask, clusters, np.arange(1, count + 1), order=1)
    out = out[0] if np.asarray(image).ndim == 2 else np.moveaxis(out, 0, -1)
    return cast(np.clip(out, *_range(case)), case.truth.dtype)


def opencv(flag):
    def run(image, mask, case):
        import cv2

        m = mask.astype(np.uint8)
        if image.dtype == np.uint8 or (image.ndim == 2 and image.dtype == np.uint16):
            return cv2.inpaint(image, m, 3, flag)
        if image.ndim == 2:  # float: OpenCV takes 32-bit float grey
            data = np.where(mask, 0, image).astype(np.float32)
            return cast(cv2.inpaint(data, m, 3, flag), image.dtype)
        return from_u8(cv2.inpaint(to_u8(image, case), m, 3, flag), case)

    return run


def fsr(flag_name):
    def run(image, mask, case):
        import cv2

        flag = getattr(cv2.xphoto, flag_name)
        u8 = (
            image
            if image.dtype == np.uint8
            else to_u8(
                np.where(mask[..., None] if image.ndim == 3 else mask, 0, np.nan_to_num(image)),
                case,
            )
        )
        known = np.where(mask, 0, 255).astype(np.uint8)
        dst = np.zeros_like(u8)
        cv2.xphoto.inpaint(u8, known, dst, flag)
        return dst if image.dtype == np.uint8 else from_u8(dst, case)

    return run


def patchmatch(image, mask, case):
    from patchmatch import patch_match

    patch_match.set_random_seed(0)
    u8 = image if image.dtype == np.uint8 else to_u8(np.nan_to_num(image), case)
    out = patch_match.inpaint(_rgb(u8), mask.astype(np.uint8), patch_size=3)
    out = out[..., 0] if image.ndim == 2 else out
    return out if image.dtype == np.uint8 else from_u8(out, case)


# Columns run only when named in --extra: the self-validated vote and cheaper votes (their
# candidate sets), and cheaper settings of the spectral default: the choices that
# docs/inpainting.md reports on the calibration half.
EXTRA = {
    "clpde-auto": ("auto", {}, None),
    "vote-cs": ("auto", {}, ("coherence", "spectral")),
    "vote-bcs": ("auto", {}, ("biharmonic", "coherence", "spectral")),
    "vote-bs": ("auto", {}, ("biharmonic", "spectral")),
    "spec-s1-i100": ("spectral", {"shifts": 1}, None),
    "spec-s2-i50": ("spectral", {"iterations": 50}, None),
    "spec-s1-i50": ("spectral", {"shifts": 1, "iterations": 50}, None),
    "spec-s2-stop01": ("spectral", {"stop": 0.01}, None),
    "spec-s2-pp2": ("spectral", {"per_pixel": 2.0}, None),
    "spec-s1-pp2": ("spectral", {"shifts": 1, "per_pixel": 2.0}, None),
}


def extra_method(name):
    """A column of EXTRA: clpde.inpaint with its method, options and vote candidates."""
    method, options, candidates = EXTRA[name]

    def run(image, mask, case):
        import clpde
        from clpde.inpainting import auto

        saved = auto.CANDIDATES
        auto.CANDIDATES = candidates or saved
        try:
            out, info = clpde.inpaint(
                image,
                mask,
                channel_axis=case.channel_axis,
                progress=False,
                seed=0,
                method=method,
                return_info=True,
                **options,
            )
            CHOSEN[0] = _chosen(info)
            return out
        finally:
            auto.CANDIDATES = saved

    return run


def methods():
    from clpde import inpainting

    found = {f"clpde-{name}": clpde_method(name) for name in inpainting.available()}
    found["default"] = clpde_method("default")
    found.update({"biharmonic": biharmonic, "harmonic": harmonic})
    try:
        import cv2

        found["opencv-ns"] = opencv(cv2.INPAINT_NS)
        found["opencv-telea"] = opencv(cv2.INPAINT_TELEA)
        if hasattr(cv2, "xphoto"):
            found["fsr-fast"] = fsr("INPAINT_FSR_FAST")
            found["fsr-best"] = fsr("INPAINT_FSR_BEST")
    except ImportError:
        print("OpenCV is missing: pip install opencv-contrib-python-headless")
    try:
        importlib.import_module("patchmatch.patch_match")
        found["patchmatch"] = patchmatch
    except Exception as error:  # its import compiles a C++ library: report why it failed
        print(f"PyPatchMatch unavailable: {error}")
    return found


# ---- the run -------------------------------------------------------------------------------
def warm_up(found):
    """One call per clpde method on a small grey and a colour image: program builds left out."""
    rng = np.random.default_rng(0)
    grey = (rng.random((40, 40)) * 255).astype(np.uint8)
    colour = (rng.random((40, 40, 3)) * 255).astype(np.uint8)
    mask = np.zeros((40, 40), bool)
    mask[15:25, 12:30] = True
    mask[5, 3:20] = True
    for name, fn in found.items():
        if name.startswith("clpde") or name == "default":
            for image in (grey, colour, grey.astype(np.uint16) * 200, grey.astype(np.float32)):
                case = corpus.Case(
                    "warm",
                    "warm",
                    "none",
                    "blobs",
                    image,
                    mask,
                    "uint8" if image.dtype == np.uint8 else "float",
                )
                fn(np.where(mask[..., None] if image.ndim == 3 else mask, 0, image), mask, case)


def interleaved(cases):
    """The halves alternating, so that a run cut short still covers both."""
    halves = [[c for c in cases if c.half == h] for h in ("test", "calibration")]
    out = []
    for i in range(max(map(len, halves))):
        out += [h[i] for h in halves if i < len(h)]
    return out


def score(case, result, name, seconds, truth=None):
    c = (
        case
        if truth is None
        else corpus.Case(case.name, case.source, case.half, case.damage, truth, case.mask, "uint8")
    )
    return {
        "case": case.name,
        "half": case.half,
        "damage": case.damage,
        "kind": case.kind,
        "method": name,
        "psnr": corpus.psnr(c, result),
        "ssim": corpus.ssim(c, result),
        "seconds": seconds,
        "outside_kept": bool(
            np.array_equal(np.asarray(result)[~case.mask], c.damaged()[~case.mask], equal_nan=True)
        ),
    }


def run_case(case, found, log):
    rows = []
    image = case.damaged()
    for name, fn in found.items():
        start = time.perf_counter()
        CHOSEN[0] = None
        try:
            result = fn(image, case.mask, case)
            rows.append(score(case, result, name, time.perf_counter() - start))
            if CHOSEN[0] is not None:
                rows[-1]["chosen"] = CHOSEN[0]
        except Exception as error:
            rows.append(
                {
                    "case": case.name,
                    "half": case.half,
                    "damage": case.damage,
                    "kind": case.kind,
                    "method": name,
                    "psnr": math.nan,
                    "ssim": math.nan,
                    "seconds": math.nan,
                    "error": f"{type(error).__name__}: {error}",
                }
            )
            traceback.print_exc()
    if case.kind != "uint8":  # the same on the 8-bit version of the data
        truth8 = to_u8(case.truth, case)
        c8 = corpus.Case(case.name, case.source, case.half, case.damage, truth8, case.mask, "uint8")
        for name in ("default", "fsr-fast", "fsr-best"):
            if name in found:
                start = time.perf_counter()
                result = found[name](c8.damaged(), case.mask, c8)
                rows.append(
                    score(
                        case,
                        result,
                        f"{name} (8-bit data)",
                        time.perf_counter() - start,
                        truth=truth8,
                    )
                )
    for r in rows:
        log.write(json.dumps(r) + "\n")
    log.flush()
    return rows


def summarise(rows, halves):
    """{half: {damage: {method: {psnr, ssim, seconds}}, "_default": {...}}}"""
    out = {}
    peers = [m for m in PEERS if any(r["method"] == m for r in rows)]
    for half in halves:
        out[half] = {}
        for damage in corpus.CLASSES:
            sel = [r for r in rows if r["half"] == half and r["damage"] == damage]
            if not sel:
                continue
            per = {}
            for m in dict.fromkeys(r["method"] for r in sel):
                rs = [r for r in sel if r["method"] == m]
                per[m] = {
                    "psnr": _mean(r["psnr"] for r in rs),
                    "ssim": _mean(r["ssim"] for r in rs),
                    "seconds": float(np.nansum([r["seconds"] for r in rs])),
                    "n": len(rs),
                }
            if "default" not in per or not any(p in per for p in peers):
                out[half][damage] = {"methods": per}  # a partial run: the methods' means only
                continue
            by_case = {}
            for r in sel:
                by_case.setdefault(r["case"], {})[r["method"]] = r["psnr"]
            margins = []
            for name, scores in by_case.items():
                best = max((scores[p], p) for p in peers if p in scores and np.isfinite(scores[p]))
                margins.append((scores.get("default", math.nan) - best[0], name, best[1]))
            wins = sum(m > 0 for m, _, _ in margins)
            worst = min(margins)
            best_peer = max((per[p]["psnr"], p) for p in peers if p in per)
            bih = per.get("biharmonic", {}).get("seconds", math.nan)
            fsr_fast = per.get("fsr-fast", {}).get("seconds", math.nan)
            out[half][damage] = {
                "methods": per,
                "cases": len(by_case),
                "default_wins": wins,
                "worst": {"margin": worst[0], "case": worst[1], "peer": worst[2]},
                "best_peer": best_peer[1],
                "lead": per["default"]["psnr"] - best_peer[0],
                "time_vs_biharmonic": per["default"]["seconds"] / bih,
                "time_vs_fsr_fast": per["default"]["seconds"] / fsr_fast,
            }
    return out


def _mean(values):
    v = [x for x in values if np.isfinite(x)]
    return float(np.mean(v)) if v else math.nan


def print_tables(summary, halves):
    def cell(half, damage, method, key, fmt):
        try:
            return format(summary[half][damage]["methods"][method][key], fmt)
        except KeyError:
            return "-"

    methods_seen = list(
        dict.fromkeys(m for h in halves for d in summary[h].values() for m in d["methods"])
    )
    for key, fmt, title in (
        ("psnr", ".2f", "mean PSNR in the hole, dB"),
        ("ssim", ".3f", "mean SSIM in the hole"),
    ):
        print(f"\n{title} ({' / '.join(halves)})")
        print(f"{'method':26s}" + "".join(f"{d:>16s}" for d in corpus.CLASSES))
        for m in methods_seen:
            cells = [" / ".join(cell(h, d, m, key, fmt) for h in halves) for d in corpus.CLASSES]
            print(f"{m:26s}" + "".join(f"{c:>16s}" for c in cells))
    print(f"\nthe default per class ({' / '.join(halves)})")
    print(
        f"{'class':11s} {'cases':>9s} {'wins':>9s} {'lead dB':>13s} {'best peer':>25s} "
        f"{'worst dB':>15s}  {'default s':>13s} {'x biharm.':>13s} {'x FSR-fast':>13s}"
    )
    for d in corpus.CLASSES:
        s = [summary[h].get(d) for h in halves]
        if not all(s) or not all("lead" in x for x in s):
            continue

        def j(f, s=s):
            return " / ".join(f(x) for x in s)

        print(
            f"{d:11s} {j(lambda x: str(x['cases'])):>9s} "
            f"{j(lambda x: str(x['default_wins'])):>9s} "
            f"{j(lambda x: format(x['lead'], '+.2f')):>13s} {j(lambda x: x['best_peer']):>25s} "
            f"{j(lambda x: format(x['worst']['margin'], '+.2f')):>15s}  "
            f"{j(lambda x: format(x['methods']['default']['seconds'], '.2f')):>13s} "
            f"{j(lambda x: format(x['time_vs_biharmonic'], '.2f')):>13s} "
            f"{j(lambda x: format(x['time_vs_fsr_fast'], '.3f')):>13s}"
        )
    for h in halves:
        worst = [
            (
                summary[h][d]["worst"]["margin"],
                d,
                summary[h][d]["worst"]["case"],
                summary[h][d]["worst"]["peer"],
            )
            for d in corpus.CLASSES
            if "worst" in summary[h].get(d, {})
        ]
        print(
            f"worst cases ({h}): " + "; ".join(f"{d} {c} {m:+.2f} vs {p}" for m, d, c, p in worst)
        )


def print_auto(rows, halves, name="clpde-auto"):
    """Per class and half: what `name` filled the holes with (mean share of the pixels), and
    its margin to its best candidate, case by case (the candidates: auto.CANDIDATES's
    clpde columns, scikit-image's fill standing in for the device's biharmonic one)."""
    from clpde.inpainting import auto

    cols = {c: ("biharmonic" if c == "biharmonic" else f"clpde-{c}") for c in auto.CANDIDATES}
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"], {})[r["method"]] = r
    if not any(name in v for v in by_case.values()):
        return
    print(f"\n{name}: its choice and its margin to its best candidate ({' / '.join(halves)})")
    print(f"{'class':11s} {'worst dB':>15s} {'cases < -0.2':>13s}  chosen (share of pixels)")
    for d in corpus.CLASSES:
        cells, shares = [], []
        for h in halves:
            margins, share = [], {}
            for scores in by_case.values():
                a = scores.get(name)
                if not a or a["half"] != h or a["damage"] != d:
                    continue
                # (the default is the spectral fill: its column stands in when the spectral
                # one was not run)
                cand = [
                    scores[c if c in scores or c != "clpde-spectral" else "default"]["psnr"]
                    for c in cols.values()
                    if c in scores or (c == "clpde-spectral" and "default" in scores)
                ]
                if cand:
                    margins.append(a["psnr"] - max(cand))
                for m, v in a.get("chosen", {}).items():
                    share[m] = share.get(m, 0.0) + v
            n = max(sum(share.values()), 1e-9)
            shares.append(
                ", ".join(
                    f"{m} {v / n:.2f}"
                    for m, v in sorted(share.items(), key=lambda x: -x[1])
                    if v / n >= 0.01
                )
            )
            cells.append(
                (min(margins, default=math.nan), sum(m < -0.2 for m in margins), len(margins))
            )
        print(
            f"{d:11s} {' / '.join(format(c[0], '+.2f') for c in cells):>15s} "
            f"{' / '.join(f'{c[1]}/{c[2]}' for c in cells):>13s}  {' | '.join(shares)}"
        )


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="one case per class and half")
    parser.add_argument("--half", choices=("test", "calibration", "both"), default="both")
    parser.add_argument("--only", default=None, help="comma-separated method names")
    parser.add_argument("--skip", default=None, help="comma-separated method names")
    parser.add_argument(
        "--slice", default=None, help="START:STOP of the (interleaved) cases: a run split by cases"
    )
    parser.add_argument(
        "--extra", default="", help=f"comma-separated extra columns: {', '.join(EXTRA)}"
    )
    parser.add_argument("--damage", default=None, help="comma-separated classes only")
    parser.add_argument(
        "--more",
        action="store_true",
        help="add tests/cases/inpaint_depth.py's rendered disparity maps (calibration only)",
    )
    parser.add_argument("--json", type=Path, default=RESULTS)
    parser.add_argument("--log", type=Path, default=None, help="JSON lines, one per result")
    parser.add_argument(
        "--from-log",
        type=Path,
        nargs="+",
        default=None,
        help="summarise earlier runs' logs instead of running (a run split "
        "by --only / --skip is summarised from its parts)",
    )
    args = parser.parse_args(argv)
    halves = ("test", "calibration") if args.half == "both" else (args.half,)
    if args.from_log:
        rows, seen = [], set()
        for path in args.from_log:  # a (case, method) met twice: the first log's row
            for line in path.read_text().splitlines():
                row = json.loads(line) if line else None
                if row and (row["case"], row["method"]) not in seen:
                    seen.add((row["case"], row["method"]))
                    rows.append(row)
    else:
        found = methods()
        found.update({name: extra_method(name) for name in filter(None, args.extra.split(","))})
        if args.only:
            found = {k: v for k, v in found.items() if k in args.only.split(",")}
        if args.skip:
            found = {k: v for k, v in found.items() if k not in args.skip.split(",")}
        print("methods:", ", ".join(found))
        warm_up(found)
        built = corpus.build(args.quick)
        if args.more:  # (every one on the calibration half: never the test half's cases)
            from tests.cases import inpaint_depth

            built += inpaint_depth.build()
        if args.damage:
            built = [c for c in built if c.damage in args.damage.split(",")]
        cases = interleaved([c for c in built if c.half in halves])
        if args.slice:
            start, stop = (int(v) if v else None for v in args.slice.split(":"))
            cases = cases[start:stop]
        print(f"{len(cases)} cases")
        log_path = args.log or args.json.with_suffix(".log.jsonl")
        log_path.parent.mkdir(parents=True, exist_ok=True)
        rows = []
        with open(log_path, "w") as log:
            for i, case in enumerate(cases):
                start = time.perf_counter()
                rows += run_case(case, found, log)
                print(
                    f"[{i + 1}/{len(cases)}] {case.name} ({case.half}) "
                    f"{time.perf_counter() - start:.1f} s",
                    flush=True,
                )
    summary = summarise(rows, halves)
    print_tables(summary, halves)
    print_auto(rows, halves)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
