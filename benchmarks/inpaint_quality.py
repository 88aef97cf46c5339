"""Inpainting quality and speed: every clpde method against OpenCV and scikit-image, in one run.

    python benchmarks/inpaint_quality.py [--json PATH] [--quick] [--no-huge]

Cases (each image x mask is one row; the table averages each class):
- text, scratches and 20-30 px blobs over seven of scikit-image's bundled photos;
- structure crossing thin holes: sharp stripes at 0, 30, 45 and 60 degrees across a
  6-pixel slot, concentric rings across a thin slot, a smooth curved edge, a T-junction;
- thick holes of 60-100 px in photos;
- texture cases of benchmarks/inpaint_texture_cases.py, where that file exists;
- a timing row: a 20000x20000 uint8 image with a 20x50 mask (time and peak memory, each
  method in its own process).

Methods: every method registered in clpde.inpainting whose module is installed (plus the
transport with the thesis's central-difference stencil, "transport-central"), OpenCV's
INPAINT_NS and INPAINT_TELEA (radius 3) and scikit-image's inpaint_biharmonic. PSNR and
SSIM are measured inside the mask. OpenCV's INPAINT_NS is not the iterative Navier-Stokes
inpainting of Bertalmio, Bertozzi and Sapiro: like INPAINT_TELEA it fills the hole in one
fast-marching pass from the border inwards, with a different weighting of the known
neighbours; clpde's method="navier-stokes" solves the vorticity transport to a steady state.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

# the repository's root, for the cases shared with the tests (tests/cases/)
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.cases.inpaint_slots import (  # noqa: E402
    _u8,
    curved_edge_case,
    edge_case,
    rings_case,
    stripes_case,
    t_junction_case,
)

RESULTS = Path(__file__).resolve().parent / "results" / "inpaint_quality.json"
PHOTOS = ("camera", "astronaut", "coffee", "chelsea", "rocket", "immunohistochemistry", "clock")


# ---- masks -------------------------------------------------------------------------------
def text_mask(shape, fraction=0.10, seed=0):
    """Overlaid text (as dates or captions are), lines until `fraction` of the pixels."""
    import cv2

    rng = np.random.default_rng(seed)
    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    words = ["clpde", "inpainting", "2001", "isophotes", "Navier", "Stokes", "sample", "text"]
    scale = max(0.5, nx / 512 * 1.1)
    thick = max(1, round(nx / 512 * 3))
    y = int(30 * scale)
    while mask.mean() < fraction and y < ny:
        line = " ".join(rng.choice(words, 3))
        cv2.putText(
            mask,
            line,
            (int(rng.integers(0, nx // 8)), y),
            cv2.FONT_HERSHEY_SIMPLEX,
            scale,
            1,
            thick,
            cv2.LINE_AA,
        )
        y += int(34 * scale)
    return mask > 0


def scratch_mask(shape, count=12, seed=1):
    """Thin scratches: random smooth curves 1-3 pixels wide."""
    import cv2

    rng = np.random.default_rng(seed)
    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    for _ in range(count):
        p0 = rng.uniform([0, 0], [nx, ny])
        angle = rng.uniform(0, np.pi)
        t = np.linspace(-0.5, 0.5, 40)[:, None] * rng.uniform(0.4, 1.0) * nx
        bend = rng.uniform(-0.15, 0.15) * t**2 / nx
        d = np.array([np.cos(angle), np.sin(angle)])
        pts = p0 + t * d + bend * np.array([-d[1], d[0]])
        cv2.polylines(mask, [pts.astype(np.int32)], False, 1, int(rng.integers(1, 4)))
    return mask > 0


def blob_mask(shape, count=8, seed=2):
    """Round blobs of 20-30 pixels diameter."""
    rng = np.random.default_rng(seed)
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx]
    mask = np.zeros(shape, bool)
    for _ in range(count):
        d = rng.uniform(20, 30)
        cy, cx = rng.uniform(d, ny - d), rng.uniform(d, nx - d)
        mask |= np.hypot(y - cy, x - cx) <= d / 2
    return mask


def thick_mask(shape, size, seed=3, square=True):
    """One square (or disc) hole of `size` pixels, placed in the middle third."""
    rng = np.random.default_rng(seed)
    ny, nx = shape
    cy, cx = int(rng.uniform(ny / 3, 2 * ny / 3)), int(rng.uniform(nx / 3, 2 * nx / 3))
    mask = np.zeros(shape, bool)
    if square:
        mask[cy - size // 2 : cy - size // 2 + size, cx - size // 2 : cx - size // 2 + size] = True
    else:
        y, x = np.mgrid[0:ny, 0:nx]
        mask = np.hypot(y - cy, x - cx) <= size / 2
    return mask


# ---- metrics -----------------------------------------------------------------------------
def psnr_in_mask(result, truth, mask):
    d = result.astype(np.float64)[mask] - truth.astype(np.float64)[mask]
    mse = float(np.mean(d**2))
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


def ssim_in_mask(result, truth, mask):
    from skimage.metrics import structural_similarity

    axis = -1 if truth.ndim == 3 else None
    _, full = structural_similarity(truth, result, data_range=255, channel_axis=axis, full=True)
    if full.ndim == 3:
        full = full.mean(axis=-1)
    return float(full[mask].mean())


# ---- why oblique isophotes fail ----------------------------------------------------
def _rate_residual(image, stencil):
    """max |I_t| of one transport step on the exact image, away from the border (numpy
    reference of the kernel, tests/reference/inpaint.py)."""
    from tests.reference.inpaint import transport_rate
    from tests.reference.planar import pad_neumann

    p = pad_neumann(image[None] / 255.0)
    return float(np.abs(transport_rate(p, stencil=stencil))[0, 8:-8, 8:-8].max())


def _from_truth(image, mask, steps, **params):
    """PSNR in the slot after `steps` steps started from the exact image."""
    import clpde
    from clpde.inpainting.transport import LevelSolver
    from clpde.inpainting.transport_params import InpaintParams

    p = InpaintParams(tol=0, mean_tol=0, **params)
    solver = LevelSolver(clpde.get_runtime(), image[None] / 255.0, mask, p)
    solver.presmooth(p.presmooth)
    for _ in solver.run(steps, 0.0):
        pass
    out = _u8(solver.result()[0])
    return psnr_in_mask(out, image, mask)


def diagnose():
    """Experiments on a straight edge and on sharp stripes crossing a 6-pixel slot at 0, 30,
    45, 60 and 90 degrees: PSNR in the slot for the candidates (the start, the
    stopping rule, the pre-smoothing, the diffusion interleave, the stencil), the residual
    of the exact image, and the drift of a run started from the exact image."""
    from skimage.restoration import inpaint_biharmonic

    variants = {
        "default": {},
        "steady": dict(tol=0, mean_tol=0, max_steps=3000),
        "presmooth=0": dict(presmooth=0),
        "B=0": dict(diffusion_steps=0),
        "harmonic start": dict(fill="diffusion"),
        "central": dict(stencil="central"),
        "central steady": dict(stencil="central", tol=0, mean_tol=0, max_steps=3000),
    }
    rows = []
    print("\nPSNR (dB) in the slot, one level; isotropic stencil unless 'central'\n")
    print("| case | biharmonic | " + " | ".join(variants) + " |")
    print("|---|---|" + "---|" * len(variants))
    for kind, make in (("edge", edge_case), ("stripes", stripes_case)):
        for angle in (0, 30, 45, 60, 90):
            image, mask = make(angle)
            bih = _u8(inpaint_biharmonic(image / 255.0, mask))
            row = {"case": f"{kind}-{angle}", "biharmonic": psnr_in_mask(bih, image, mask)}
            for name, options in variants.items():
                out = run_clpde(image, mask, levels=1, **options)
                row[name] = psnr_in_mask(out, image, mask)
            rows.append(row)
            print(
                "| "
                + " | ".join([row["case"]] + [f"{row[k]:.1f}" for k in ["biharmonic", *variants]])
                + " |",
                flush=True,
            )
    print(
        "\nThe exact image: max |I_t| of one step (numpy reference), and the PSNR in the slot "
        "after 300 / 3000 steps started from it (no pre-smoothing, no diffusion)\n"
    )
    print(
        "| case | residual central | residual isotropic | central 300 / 3000 | "
        "isotropic 300 / 3000 |"
    )
    print("|---|---|---|---|---|")
    exact = []
    for kind, make in (("edge", edge_case), ("stripes", stripes_case)):
        for angle in (0, 30, 45, 60):
            image, mask = make(angle)
            r = {"case": f"{kind}-{angle}"}
            for stencil in ("central", "isotropic"):
                r[f"residual_{stencil}"] = _rate_residual(image, stencil)
                r[f"drift_{stencil}"] = [
                    _from_truth(image, mask, n, stencil=stencil, presmooth=0, diffusion_steps=0)
                    for n in (300, 3000)
                ]
            exact.append(r)
            print(
                f"| {r['case']} | {r['residual_central']:.1e} | {r['residual_isotropic']:.1e} | "
                f"{r['drift_central'][0]:.1f} / {r['drift_central'][1]:.1f} | "
                f"{r['drift_isotropic'][0]:.1f} / {r['drift_isotropic'][1]:.1f} |",
                flush=True,
            )
    return {"variants": rows, "exact": exact}


# ---- methods -----------------------------------------------------------------------------
def run_cv2(image, mask, flag):
    import cv2

    return cv2.inpaint(image, mask.astype(np.uint8), 3, flag)


def run_biharmonic(image, mask):
    from skimage.restoration import inpaint_biharmonic

    axis = -1 if image.ndim == 3 else None
    out = inpaint_biharmonic(image, mask, channel_axis=axis)
    return np.clip(np.rint(out * 255), 0, 255).astype(np.uint8)


def run_clpde(image, mask, **options):
    import clpde

    axis = -1 if image.ndim == 3 else None
    return clpde.inpaint(image, mask, channel_axis=axis, progress=False, **options)


def methods(only=None):
    """{name: fn(image, mask)}: the clpde methods installed, then the peers."""
    import cv2

    from clpde.inpainting.registry import available

    table = {}
    for name in available():
        table[name] = lambda im, m, name=name: run_clpde(im, m, method=name)
        if name == "transport":
            table["transport-central"] = lambda im, m: run_clpde(
                im, m, method="transport", stencil="central"
            )
    table["auto"] = lambda im, m: run_clpde(im, m, method="auto")
    table.update(
        {
            "opencv-ns": lambda im, m: run_cv2(im, m, cv2.INPAINT_NS),
            "opencv-telea": lambda im, m: run_cv2(im, m, cv2.INPAINT_TELEA),
            "skimage-biharmonic": run_biharmonic,
        }
    )
    if only:
        table = {k: v for k, v in table.items() if k in only}
    return table


PEERS = ("opencv-ns", "opencv-telea", "skimage-biharmonic")


def texture_cases():
    """(class, name, image, mask) from benchmarks/inpaint_texture_cases.py, if present:
    its classes prefixed 'texture-' unless already 'texture'; float images as uint8."""
    try:
        import inpaint_texture_cases as tc
    except ImportError:
        return []
    out = []
    for case in tc.texture_cases():
        image = case["image"]
        if np.issubdtype(image.dtype, np.floating):
            image = _u8(image)
        kind = case["class"] if case["class"] == "texture" else f"texture-{case['class']}"
        out.append((kind, case["name"], image, case["mask"]))
    return out


def edge_energy(result, truth, mask):
    """The texture's energy kept in the hole (benchmarks/inpaint_texture_cases.py), or None."""
    try:
        import inpaint_texture_cases as tc
    except ImportError:
        return None
    return float(tc.edge_energy(result, truth, mask))


def cases(quick=False):
    from skimage import data

    names = PHOTOS[:2] if quick else PHOTOS
    out = []
    for name in names:
        image = getattr(data, name)()
        shape = image.shape[:2]
        out.append(("text", name, image, text_mask(shape)))
        out.append(("scratches", name, image, scratch_mask(shape)))
        out.append(("blobs", name, image, blob_mask(shape)))
    for angle in (0, 30, 45, 60):
        out.append(("structure", f"stripes-{angle}", *stripes_case(angle)))
    for angle in (30, 60):
        out.append(("structure", f"edge-{angle}", *edge_case(angle)))
    out.append(("structure", "rings", *rings_case()))
    out.append(("structure", "curved-edge", *curved_edge_case()))
    out.append(("structure", "t-junction", *t_junction_case()))
    thick = [
        ("coffee", 100, True),
        ("camera", 80, True),
        ("astronaut", 60, False),
        ("chelsea", 70, True),
        ("rocket", 90, False),
    ]
    for name, size, square in thick[:1] if quick else thick:
        image = getattr(data, name)()
        out.append(
            ("thick", f"{name}-{size}", image, thick_mask(image.shape[:2], size, square=square))
        )
    out.extend(texture_cases())
    return out


def quality(quick=False, only=None):
    rows = []
    table = methods(only)
    run_clpde(np.zeros((32, 32, 3), np.uint8), np.eye(32, dtype=bool))  # build the kernels
    for kind, name, image, mask in cases(quick):
        for method, fn in table.items():
            start = time.perf_counter()
            try:
                result = fn(image, mask)
            except Exception as error:  # a method that fails is a row, not the end of the run
                print(f"  {kind:10s} {name:22s} {method:19s} FAILED: {error}", file=sys.stderr)
                continue
            seconds = time.perf_counter() - start
            assert result.dtype == image.dtype and result.shape == image.shape
            rows.append(
                {
                    "class": kind,
                    "image": name,
                    "method": method,
                    "seconds": seconds,
                    "psnr": psnr_in_mask(result, image, mask),
                    "ssim": ssim_in_mask(result, image, mask),
                    "edge_energy": edge_energy(result, image, mask),
                    "coverage": float(mask.mean()),
                }
            )
            print(
                f"  {kind:10s} {name:22s} {method:19s} PSNR {rows[-1]['psnr']:6.2f}  "
                f"SSIM {rows[-1]['ssim']:.3f}  {seconds:7.3f} s",
                file=sys.stderr,
                flush=True,
            )
    return rows


HUGE = """
import resource, sys, time
import numpy as np
n, method = {n}, {method!r}
image = np.full((n, n), 128, np.uint8)
image[:, ::7] = 40
mask = np.zeros((n, n), bool)
mask[n // 4: n // 4 + 20, n // 3: n // 3 + 50] = True
peers = ("opencv-ns", "opencv-telea", "skimage-biharmonic")
if not method.startswith("transport") and method in peers:
    # peers get 8 GiB of address space, so that one that grows with the image fails
    # with a MemoryError instead of crowding the machine
    resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))
if method.startswith("opencv"):
    import cv2
    flag = cv2.INPAINT_NS if method == "opencv-ns" else cv2.INPAINT_TELEA
    run = lambda: cv2.inpaint(image, mask.astype(np.uint8), 3, flag)
elif method == "skimage-biharmonic":
    from skimage.restoration import inpaint_biharmonic
    run = lambda: inpaint_biharmonic(image, mask)
else:
    import clpde
    clpde.inpaint(image[:64, :64], mask[:64, :64], method=method, progress=False)
    run = lambda: clpde.inpaint(image, mask, method=method, progress=False)
start = time.perf_counter()
run()
seconds = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(seconds, peak / 2**20, (2 * image.nbytes + mask.nbytes) / 2**30)
"""


def huge(n=20000, timeout=300, only=None):
    """Time and peak memory (GiB) on an n x n uint8 image with a 20x50 mask, one process per
    method (peers limited to 8 GiB of address space); input (image and bool mask) plus
    output is 3 n^2 bytes."""
    rows = []
    names = [m for m in methods(only) if m != "transport-central"]
    for method in names:
        code = HUGE.format(n=n, method=method)
        try:
            done = subprocess.run(
                [sys.executable, "-c", code],
                capture_output=True,
                text=True,
                timeout=timeout,
                env=dict(os.environ),
            )
        except subprocess.TimeoutExpired:
            rows.append(
                {"method": method, "seconds": None, "peak_gb": None, "note": f"over {timeout} s"}
            )
            continue
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or [f"exit status {done.returncode}"])[-1]
            rows.append({"method": method, "seconds": None, "peak_gb": None, "note": last[:120]})
        else:
            seconds, peak, io = map(float, done.stdout.split())
            rows.append(
                {
                    "method": method,
                    "seconds": seconds,
                    "peak_gb": peak,
                    "input_plus_output_gb": io,
                    "note": "",
                }
            )
        print(f"  {n}x{n}: {rows[-1]}", file=sys.stderr, flush=True)
    return rows


PSNR_CAP = 60.0  # an exact fill (periodic structure copied whole) counts as 60 dB in means


def summarise(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["class"], r["method"]), []).append(r)
    summary = []
    for (kind, method), rs in groups.items():
        summary.append(
            {
                "class": kind,
                "method": method,
                "n": len(rs),
                "psnr": float(np.mean([min(r["psnr"], PSNR_CAP) for r in rs])),
                "ssim": float(np.mean([r["ssim"] for r in rs])),
                "seconds": float(np.mean([r["seconds"] for r in rs])),
                "edge_energy": None
                if rs[0]["edge_energy"] is None
                else float(np.mean([r["edge_energy"] for r in rs])),
            }
        )
    return summary


def print_table(summary, huge_rows):
    print(
        "Inpainting quality inside the mask (mean over the cases of each class; PSNR "
        f"capped at {PSNR_CAP:g} dB)\n"
    )
    print("| class | method | cases | PSNR (dB) | SSIM | edge energy | time (s) |")
    print("|---|---|---|---|---|---|---|")
    for s in summary:
        energy = "-" if s["edge_energy"] is None else f"{s['edge_energy']:.2f}"
        print(
            f"| {s['class']} | {s['method']} | {s['n']} | {s['psnr']:.2f} | {s['ssim']:.3f} | "
            f"{energy} | {s['seconds']:.3f} |"
        )
    if huge_rows:
        print(
            "\n20000x20000 uint8, 20x50 mask (own process each; image + bool mask + output = "
            "1.12 GiB)\n"
        )
        print("| method | time (s) | peak memory (GiB) | note |")
        print("|---|---|---|---|")
        for r in huge_rows:
            t = "-" if r["seconds"] is None else f"{r['seconds']:.2f}"
            m = "-" if r["peak_gb"] is None else f"{r['peak_gb']:.2f}"
            print(f"| {r['method']} | {t} | {m} | {r['note']} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", default=str(RESULTS), help=f"JSON output (default {RESULTS})")
    parser.add_argument("--quick", action="store_true", help="fewer photos, for a smoke test")
    parser.add_argument("--no-huge", action="store_true", help="skip the 20000x20000 row")
    parser.add_argument("--methods", nargs="*", default=None, help="only these methods")
    parser.add_argument(
        "--diagnose", action="store_true", help="only the experiments on oblique isophotes"
    )
    args = parser.parse_args(argv)
    import clpde

    if args.diagnose:
        result = diagnose()
        path = Path(args.json).with_name("inpaint_diagnosis.json")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=2))
        print(f"\nwrote {path}", file=sys.stderr)
        return

    device = clpde.get_runtime().device
    rows = quality(args.quick, args.methods)
    summary = summarise(rows)
    huge_rows = [] if args.no_huge else huge(only=args.methods)
    print_table(summary, huge_rows)
    out = {
        "device": f"{device.name.strip()} ({device.platform.name.strip()})",
        "cpu_count": os.cpu_count(),
        "rows": rows,
        "summary": summary,
        "huge": huge_rows,
    }
    path = Path(args.json)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(out, indent=2))
    os.replace(tmp, path)
    print(f"\nwrote {path}", file=sys.stderr)


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    main()
