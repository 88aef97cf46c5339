"""Quick quality and time of method="spectral" against clpde's default, OpenCV contrib's FSR
(fast and best) and scikit-image's biharmonic fill, on the calibration photos only.

    python benchmarks/inpaint_spectral_quick.py [--size 256] [--images a,b] [--damage text,dust]
        [--peers default,fsr-fast,fsr-best,biharmonic] [--sweep JSON] [--json PATH]

Photos: scikit-image's astronaut, coffee, chelsea, camera, brick, rocket,
immunohistochemistry, gravel and grass (the calibration half of the project's corpus; the
held-out half is never looked at here), cropped to their central `--size` square (0: whole).
Damage: text, thin scratches (inpaint_quality.py's masks), blobs 8-15 px and dust (hundreds
of 1-4 px specks). PSNR and SSIM inside the mask, in 8 bits; FSR is given the known mask
(nonzero = known) in 8 bits, as a user calls it.

--sweep '[{"rho": 0.7}, {"rho": 0.9}]' runs method="spectral" once per option set (the tuning
table in the notes comes from such runs). Times are wall times of one call after a warm-up
call on the first case (no builds counted); for spectral the split into plan, build, upload,
waves and readback is printed as well (clpde.inpainting.spectral.fill's timings).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

CALIBRATION = (
    "astronaut",
    "coffee",
    "chelsea",
    "camera",
    "brick",
    "rocket",
    "immunohistochemistry",
    "gravel",
    "grass",
)
DAMAGE = ("text", "scratches", "blobs", "dust")
PEERS = ("default", "fsr-fast", "fsr-best", "biharmonic")


def photo(name: str, size: int) -> np.ndarray:
    from skimage import data

    image = getattr(data, name)()
    if image.ndim == 3 and image.shape[-1] == 4:
        image = image[..., :3]
    if image.dtype != np.uint8:
        image = np.clip(np.rint(image * 255 if image.max() <= 1 else image), 0, 255)
        image = image.astype(np.uint8)
    if size:
        ny, nx = image.shape[:2]
        y0, x0 = max(0, (ny - size) // 2), max(0, (nx - size) // 2)
        image = image[y0 : y0 + size, x0 : x0 + size]
    return np.ascontiguousarray(image)


def blob_mask(shape, count=None, seed=2):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    count = count or max(4, ny * nx // 6000)
    y, x = np.mgrid[0:ny, 0:nx]
    mask = np.zeros(shape, bool)
    for _ in range(count):
        d = rng.uniform(8, 15)
        cy, cx = rng.uniform(d, ny - d), rng.uniform(d, nx - d)
        mask |= np.hypot(y - cy, x - cx) <= d / 2
    return mask


def dust_mask(shape, seed=4):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    count = max(100, ny * nx // 300)
    mask = np.zeros(shape, bool)
    for _ in range(count):
        s = int(rng.integers(1, 5))
        cy, cx = int(rng.integers(0, ny - s)), int(rng.integers(0, nx - s))
        mask[cy : cy + s, cx : cx + s] = True
    return mask


def damage(kind: str, shape) -> np.ndarray:
    from inpaint_quality import scratch_mask, text_mask

    return {
        "text": lambda: text_mask(shape, fraction=0.08),
        "scratches": lambda: scratch_mask(shape),
        "blobs": lambda: blob_mask(shape),
        "dust": lambda: dust_mask(shape),
    }[kind]()


def psnr(result, truth, mask) -> float:
    err = (result.astype(np.float64) - truth)[mask]
    mse = float(np.mean(err**2))
    return 10 * np.log10(255.0**2 / max(mse, 1e-12))


def ssim(result, truth, mask) -> float:
    from skimage.metrics import structural_similarity

    axis = -1 if truth.ndim == 3 else None
    _, full = structural_similarity(truth, result, channel_axis=axis, data_range=255, full=True)
    if full.ndim == 3:
        full = full.mean(-1)
    return float(full[mask].mean())


def run_peer(name, image, mask):
    import cv2

    if name == "default":
        import clpde

        axis = -1 if image.ndim == 3 else None
        return clpde.inpaint(image, mask, channel_axis=axis, progress=False)
    if name.startswith("fsr"):
        flag = cv2.xphoto.INPAINT_FSR_FAST if name == "fsr-fast" else cv2.xphoto.INPAINT_FSR_BEST
        known = np.where(mask, 0, 255).astype(np.uint8)
        out = np.zeros_like(image)
        cv2.xphoto.inpaint(image, known, out, flag)
        return out
    if name == "biharmonic":
        from skimage.restoration import inpaint_biharmonic

        axis = -1 if image.ndim == 3 else None
        out = inpaint_biharmonic(image, mask, channel_axis=axis)
        return np.clip(np.rint(out * 255), 0, 255).astype(np.uint8)
    raise ValueError(name)


def run_spectral(image, mask, options, timings=None):
    from clpde.imagedata import integer_range
    from clpde.inpainting import spectral
    from clpde.runtime import get_runtime

    planes = image[None] if image.ndim == 2 else np.moveaxis(image, -1, 0)
    offset, scale = integer_range(image.dtype)
    data = (planes.astype(np.float64) - offset) / scale
    out = spectral.fill(data, mask, get_runtime(), timings=timings, **options)
    out = np.clip(np.rint(out * scale + offset), 0, 255).astype(image.dtype)
    out = out[0] if image.ndim == 2 else np.moveaxis(out, 0, -1)
    return np.where(mask[..., None] if image.ndim == 3 else mask, out, image)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--images", default=",".join(CALIBRATION))
    ap.add_argument("--damage", default=",".join(DAMAGE))
    ap.add_argument("--peers", default=",".join(PEERS))
    ap.add_argument("--sweep", default="[{}]")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    images = [n for n in args.images.split(",") if n]
    bad = sorted(set(images) - set(CALIBRATION))
    if bad:
        raise SystemExit(f"not calibration images: {', '.join(bad)}")
    kinds = [k for k in args.damage.split(",") if k]
    peers = [p for p in args.peers.split(",") if p]
    sweep = json.loads(args.sweep)
    cases = []
    for name in images:
        image = photo(name, args.size)
        for kind in kinds:
            cases.append((name, kind, image, damage(kind, image.shape[:2])))
    # warm-up: builds and PoCL's first launches are not what the table measures
    run_spectral(cases[0][2], cases[0][3], sweep[0])
    if "default" in peers:
        run_peer("default", cases[0][2], cases[0][3])
    rows = []
    for name, kind, image, mask in cases:
        row = {"image": name, "damage": kind, "pixels": int(mask.sum()), "results": {}}
        for p in peers:
            t0 = time.perf_counter()
            out = run_peer(p, image, mask)
            dt = time.perf_counter() - t0
            row["results"][p] = dict(
                psnr=psnr(out, image, mask), ssim=ssim(out, image, mask), seconds=dt
            )
        for i, options in enumerate(sweep):
            timings = {}
            t0 = time.perf_counter()
            out = run_spectral(image, mask, options, timings)
            dt = time.perf_counter() - t0
            row["results"][f"spectral{i}"] = dict(
                psnr=psnr(out, image, mask),
                ssim=ssim(out, image, mask),
                seconds=dt,
                timings=timings,
                options=options,
            )
        rows.append(row)
        print(
            name,
            kind,
            " ".join(f"{k}={v['psnr']:.2f}/{v['seconds']:.2f}s" for k, v in row["results"].items()),
            flush=True,
        )
    names = list(rows[0]["results"])
    print(f"\nmean PSNR in the mask (dB) / SSIM / total seconds, size {args.size}")
    print("damage     " + " ".join(f"{n:>22}" for n in names))
    for kind in kinds + ["all"]:
        sel = [r for r in rows if kind in ("all", r["damage"])]
        cells = []
        for n in names:
            p = np.mean([r["results"][n]["psnr"] for r in sel])
            s = np.mean([r["results"][n]["ssim"] for r in sel])
            t = np.sum([r["results"][n]["seconds"] for r in sel])
            cells.append(f"{p:7.2f} {s:5.3f} {t:7.2f}s")
        print(f"{kind:10} " + " ".join(f"{c:>22}" for c in cells))
    for i, options in enumerate(sweep):
        keys = ("plan", "build", "upload", "waves", "readback")
        tot = {
            k: sum(r["results"][f"spectral{i}"]["timings"].get(k, 0) for r in rows) for k in keys
        }
        launches = sum(r["results"][f"spectral{i}"]["timings"].get("launches", 0) for r in rows)
        blocks = sum(r["results"][f"spectral{i}"]["timings"].get("blocks", 0) for r in rows)
        print(
            f"spectral{i} {options}: "
            + ", ".join(f"{k} {v:.2f}s" for k, v in tot.items())
            + f", {launches} launches, {blocks} blocks"
        )
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(
            json.dumps(dict(size=args.size, rows=rows), indent=1, default=float)
        )


if __name__ == "__main__":
    main()
