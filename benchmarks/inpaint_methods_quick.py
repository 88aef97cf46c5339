"""Quick quality and speed of clpde's coherence, Navier-Stokes and Poisson inpainting methods.

    python benchmarks/inpaint_methods_quick.py [--json PATH] [--cases stripes,photos,holes]
    python benchmarks/inpaint_methods_quick.py --figure docs/images/inpainting_methods.png

In one run, PSNR inside the hole and wall time of clpde.inpainting's methods (coherence
transport, Navier-Stokes, the device harmonic and biharmonic fills) against scikit-image's
inpaint_biharmonic and OpenCV's INPAINT_NS and INPAINT_TELEA (radius 3), on
- structure: sharp stripes (period 16) crossing a vertical slot 8 px wide at 0, 30, 45 and
  60 degrees from the slot's normal, and a straight edge at 30 and 60 degrees;
- photos: text and scratch masks on four of scikit-image's bundled photos (colour ones in
  colour);
- thick holes: a centred 60x60 and 100x100 square on three of them.
Times are the best of 2 runs after a warm-up (kernel builds excluded).
(benchmarks/inpaint_quality.py is the full benchmark of every registered method.)
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
RESULTS = ROOT / "benchmarks" / "results" / "inpaint_methods_quick.json"


def stripes(angle, size=96, period=16, slot=8):
    """Anti-aliased stripes whose normal makes `angle` degrees with x, a vertical slot."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    a = np.radians(angle)
    s = (x - size / 2) * np.cos(a) + (y - size / 2) * np.sin(a)
    image = np.clip(0.5 + 2.0 * np.cos(2 * np.pi * s / period), 0, 1) * 0.8 + 0.1
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 - slot // 2 : size // 2 + slot // 2] = True
    return image, mask


def edge(angle, size=96, slot=10):
    y, x = np.mgrid[0:size, 0:size].astype(float)
    a = np.radians(angle)
    s = (x - size / 2) * np.cos(a) + (y - size / 2) * np.sin(a)
    image = 0.2 + 0.6 / (1 + np.exp(-s / 0.7))
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 - slot // 2 : size // 2 + slot // 2] = True
    return image, mask


def text_mask(shape, fraction=0.06, seed=0):
    import cv2

    rng = np.random.default_rng(seed)
    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    words = ["coherence", "transport", "2007", "Navier", "Stokes", "fluid", "vorticity"]
    y = 30
    while mask.mean() < fraction and y < ny:
        cv2.putText(
            mask,
            " ".join(rng.choice(words, 3)),
            (int(rng.integers(0, nx // 8)), y),
            cv2.FONT_HERSHEY_SIMPLEX,
            nx / 512 * 1.1,
            1,
            max(1, round(nx / 512 * 3)),
            cv2.LINE_AA,
        )
        y += int(34 * nx / 512)
    return mask > 0


def scratch_mask(shape, count=10, seed=1):
    import cv2

    rng = np.random.default_rng(seed)
    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    for _ in range(count):
        p0 = rng.uniform([0, 0], [nx, ny])
        d = np.array([np.cos(a := rng.uniform(0, np.pi)), np.sin(a)])
        t = np.linspace(-0.5, 0.5, 40)[:, None] * rng.uniform(0.4, 1.0) * nx
        pts = p0 + t * d
        cv2.polylines(mask, [pts.astype(np.int32)], False, 1, int(rng.integers(1, 4)))
    return mask > 0


def photos():
    from skimage import data

    out = []
    for name in ("camera", "astronaut", "coffee", "brick"):
        img = getattr(data, name)()
        img = img.astype(np.float64) / 255
        out.append((name, img))
    return out


def psnr(result, truth, mask):
    err = (np.asarray(result, float) - truth)[mask]
    mse = float(np.mean(err**2))
    return 10 * np.log10(1 / max(mse, 1e-12))


def methods(runtime):
    import cv2
    from skimage.restoration import inpaint_biharmonic

    from clpde.inpainting import coherence, navier_stokes, poisson

    def clpde(module, **kw):
        def run(image, mask):
            planes = image[None] if image.ndim == 2 else np.moveaxis(image, -1, 0)
            out = module.solve(planes, mask, runtime, **kw)
            return out[0] if image.ndim == 2 else np.moveaxis(out, 0, -1)

        return run

    def opencv(flag):
        def run(image, mask):
            u8 = np.clip(np.rint(image * 255), 0, 255).astype(np.uint8)
            return cv2.inpaint(u8, mask.astype(np.uint8), 3, flag).astype(float) / 255

        return run

    def skimage(image, mask):
        return inpaint_biharmonic(image, mask, channel_axis=None if image.ndim == 2 else -1)

    return {
        "clpde coherence": clpde(coherence),
        "clpde navier-stokes": clpde(navier_stokes),
        "clpde harmonic": clpde(poisson, kind="harmonic"),
        "clpde biharmonic": clpde(poisson, kind="biharmonic"),
        "skimage biharmonic": skimage,
        "opencv NS": opencv(cv2.INPAINT_NS),
        "opencv Telea": opencv(cv2.INPAINT_TELEA),
    }


def cases(which):
    out = []
    if "stripes" in which:
        for a in (0, 30, 45, 60):
            out.append(("structure", f"stripes {a} deg", *stripes(a)))
        for a in (30, 60):
            out.append(("structure", f"edge {a} deg", *edge(a)))
    if "photos" in which:
        for name, img in photos():
            out.append(("text", name, img, text_mask(img.shape[:2])))
            out.append(("scratches", name, img, scratch_mask(img.shape[:2])))
    if "holes" in which:
        for name, img in photos()[:3]:
            for side in (60, 100):
                mask = np.zeros(img.shape[:2], bool)
                cy, cx = img.shape[0] // 2, img.shape[1] // 2
                mask[cy - side // 2 : cy + side // 2, cx - side // 2 : cx + side // 2] = True
                out.append(("thick", f"{name} {side}x{side}", img, mask))
    return out


def figure(path, runtime):
    """Rows: stripes at 45 degrees, an edge at 30 degrees, a crop of `coffee` with text;
    columns: damaged, then each method (the hole shown in red in the damaged column)."""
    from skimage.io import imsave

    table = methods(runtime)
    names = [
        "clpde coherence",
        "clpde navier-stokes",
        "clpde biharmonic",
        "opencv NS",
        "opencv Telea",
    ]
    img = photos()[2][1][70:198, 200:328]
    rows = [
        stripes(45, size=128),
        edge(30, size=128, slot=10),
        (img, text_mask(img.shape[:2], fraction=0.08, seed=3)),
    ]
    tiles = []
    for image, mask in rows:
        rgb = image if image.ndim == 3 else np.repeat(image[..., None], 3, -1)
        size = 256

        def fit(a):
            return np.kron(a, np.ones((2, 2, 1)))  # 128 px cases shown at 2x

        damaged = rgb.copy()
        damaged[mask] = [0.9, 0.1, 0.1]
        row = [fit(damaged)]
        for name in names:
            out = table[name](image, mask)
            out = out if out.ndim == 3 else np.repeat(out[..., None], 3, -1)
            row.append(fit(np.clip(out, 0, 1)))
        sep = np.ones((size, 4, 3))
        tiles.append(np.hstack([t for tile in row for t in (tile, sep)][:-1]))
    sheet = np.vstack([t for tile in tiles for t in (tile, np.ones((4, tile.shape[1], 3)))][:-1])
    path.parent.mkdir(parents=True, exist_ok=True)
    imsave(path, (sheet * 255).round().astype(np.uint8), check_contrast=False)
    print(f"wrote {path}: columns damaged, " + ", ".join(names))


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", type=Path, default=RESULTS)
    ap.add_argument("--cases", default="stripes,photos,holes")
    ap.add_argument("--methods", default=None, help="comma-separated subset")
    ap.add_argument("--figure", type=Path, default=None, help="write the comparison picture")
    args = ap.parse_args(argv)
    from clpde.runtime import get_runtime

    runtime = get_runtime()
    if args.figure:
        figure(args.figure, runtime)
        return
    table = methods(runtime)
    if args.methods:
        table = {k: v for k, v in table.items() if any(m in k for m in args.methods.split(","))}
    rows = []
    for kind, name, image, mask in cases(args.cases.split(",")):
        line = (
            f"{kind:10s} {name:16s} {image.shape[1]}x{image.shape[0]}"
            f"{'x3' if image.ndim == 3 else '  '} {100 * mask.mean():4.1f}%"
        )
        for method, fn in table.items():
            fn(image, mask)  # warm-up: kernel builds
            best = np.inf
            for _ in range(2):
                t = time.perf_counter()
                out = fn(image, mask)
                best = min(best, time.perf_counter() - t)
            p = psnr(out, image, mask)
            rows.append(
                dict(
                    kind=kind,
                    case=name,
                    method=method,
                    psnr=p,
                    seconds=best,
                    shape=list(image.shape),
                    mask_fraction=float(mask.mean()),
                )
            )
            line += f" | {method.split()[-1][:9]:9s} {p:5.1f} dB {best * 1e3:6.0f} ms"
        print(line, flush=True)
    print("\nMean PSNR in the hole (dB) and mean time (ms) per class:")
    for kind in dict.fromkeys(r["kind"] for r in rows):
        print(f"  {kind}:")
        for method in table:
            sel = [r for r in rows if r["kind"] == kind and r["method"] == method]
            print(
                f"    {method:22s} {np.mean([r['psnr'] for r in sel]):6.2f} dB "
                f"{1e3 * np.mean([r['seconds'] for r in sel]):8.1f} ms"
            )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(dict(device=str(runtime), rows=rows), indent=1))
    print(f"\nwrote {args.json} (device: {runtime})")


if __name__ == "__main__":
    main()
