"""3D volumes against scikit-image (issue 39): TV denoising against
skimage.restoration.denoise_tv_chambolle, and the harmonic, biharmonic and spectral (4^3 DCT
blocks) fills against inpaint_biharmonic.

Calibration half: the first frame of nibabel's test volume example4d.nii.gz (128 x 96 x 24
voxels of 2 x 2 x 2.2 mm, an EPI frame); skimage's best TV weight is chosen there. Test half:
nilearn's MNI152 template (2 mm), resampled to 64 x 80 x 64 voxels for CPU time. Both scaled
to [0, 1]; Gaussian noise of deviation SIGMA (seed 0 calibration, 1 test); the damage is
random balls and a slab of two missing slices (seed 2 and 3). PSNR over the whole volume for
denoising, over the missing voxels for inpainting. Times: the median of REPEATS runs, after a
warm-up run (clpde's kernels are built once per process).

    python benchmarks/volumes.py [--picture docs/images/volumes.png]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy import ndimage
from skimage.metrics import peak_signal_noise_ratio as psnr
from skimage.restoration import denoise_tv_chambolle, inpaint_biharmonic

import clpde
from clpde.volumes import inpaint_volume

SIGMA = 0.08
REPEATS = 3
WEIGHTS = (0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.1)


def calibration_volume():
    import nibabel
    from nibabel.testing import data_path

    data = np.asarray(nibabel.load(data_path / "example4d.nii.gz").dataobj)[..., 0]
    vol = np.ascontiguousarray(data.transpose(2, 1, 0), np.float64)  # (z, y, x)
    return (vol - vol.min()) / np.ptp(vol), (2.2, 2.0, 2.0)


def test_volume():
    from nilearn import datasets

    img = datasets.load_mni152_template(resolution=2)
    data = np.asarray(img.get_fdata()).transpose(2, 1, 0)  # (z, y, x) of (95, 117, 99)
    target = (64, 80, 64)
    vol = ndimage.zoom(data, [t / s for t, s in zip(target, data.shape, strict=True)], order=1)
    vol = (vol - vol.min()) / np.ptp(vol)
    return vol, tuple(2.0 * s / t for t, s in zip(target, data.shape, strict=True))


def timed(fn):
    fn()  # warm-up: kernel builds, caches
    times, out = [], None
    for _ in range(REPEATS):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return out, float(np.median(times))


def damage(shape, seed):
    rng = np.random.default_rng(seed)
    z, y, x = np.indices(shape)
    mask = np.zeros(shape, bool)
    for _ in range(8):
        c = [rng.integers(n // 5, 4 * n // 5) for n in shape]
        r = rng.uniform(2.5, 5.0)
        mask |= (z - c[0]) ** 2 + (y - c[1]) ** 2 + (x - c[2]) ** 2 < r * r
    k = shape[0] // 2 + int(rng.integers(-3, 4))
    mask[k : k + 2, shape[1] // 4 : 3 * shape[1] // 4, :] = True  # two slices, half the rows
    return mask


def denoise_rows(name, clean, spacing, seed, weight):
    noisy = np.clip(clean + SIGMA * np.random.default_rng(seed).standard_normal(clean.shape), 0, 1)
    ours, t_ours = timed(lambda: clpde.denoise_tv(noisy, spacing=spacing))
    ref, t_ref = timed(lambda: denoise_tv_chambolle(noisy))
    best, t_best = timed(lambda: denoise_tv_chambolle(noisy, weight=weight))
    rows = [
        (name, "noisy", psnr(clean, noisy, data_range=1), float("nan")),
        (name, "clpde.denoise_tv (sigma estimated)", psnr(clean, ours, data_range=1), t_ours),
        (name, "skimage default (weight 0.1)", psnr(clean, ref, data_range=1), t_ref),
        (name, f"skimage weight {weight:g} (calibrated)", psnr(clean, best, data_range=1), t_best),
    ]
    return rows, noisy, ours, ref


def best_weight(clean, seed):
    noisy = np.clip(clean + SIGMA * np.random.default_rng(seed).standard_normal(clean.shape), 0, 1)
    scores = {w: psnr(clean, denoise_tv_chambolle(noisy, weight=w), data_range=1) for w in WEIGHTS}
    return max(scores, key=scores.get)


def inpaint_rows(name, clean, spacing, seed):
    mask = damage(clean.shape, seed)
    damaged = np.where(mask, 0.0, clean)
    ours, t_ours = timed(lambda: inpaint_volume(damaged, mask, method="harmonic", spacing=spacing))
    bi, t_bi = timed(lambda: inpaint_volume(damaged, mask, method="biharmonic", spacing=spacing))
    sp, t_sp = timed(lambda: inpaint_volume(damaged, mask, method="spectral", spacing=spacing))
    ref, t_ref = timed(lambda: inpaint_biharmonic(damaged, mask))

    def hole(v):
        return psnr(clean[mask], v[mask], data_range=1)

    rows = [
        (name, f"clpde.volumes.inpaint_volume (harmonic), {mask.mean():.1%} missing",
         hole(ours), t_ours),
        (name, "clpde.volumes.inpaint_volume (biharmonic)", hole(bi), t_bi),
        (name, "clpde.volumes.inpaint_volume (spectral)", hole(sp), t_sp),
        (name, "skimage inpaint_biharmonic", hole(ref), t_ref),
    ]  # fmt: skip
    return rows, damaged, bi, ref, mask  # the default fill in the picture


def table(rows, title):
    print(f"\n{title}\n")
    print("| volume | method | PSNR (dB) | time (s) |\n|---|---|---|---|")
    for name, method, p, t in rows:
        print(f"| {name} | {method} | {p:.2f} | {'' if np.isnan(t) else f'{t:.2f}'} |")


def picture(path, clean, noisy, tv_ours, tv_ref, damaged, fill_ours, fill_ref):
    """Axial (top) and coronal (bottom) slices through the missing slab, with labels (Pillow)."""
    from PIL import Image, ImageDraw

    k = clean.shape[0] // 2 + 1
    panels = [
        ("clean", clean), ("noisy", noisy), ("clpde TV", tv_ours), ("skimage TV", tv_ref),
        ("damaged", damaged), ("clpde biharmonic", fill_ours), ("skimage biharmonic", fill_ref),
    ]  # fmt: skip
    scale, label = 3, 18
    tiles = []
    for title, vol in panels:
        axial = vol[k][::-1]
        coronal = vol[:, vol.shape[1] // 2][::-1]
        width = max(axial.shape[1], coronal.shape[1])
        col = np.zeros((axial.shape[0] + coronal.shape[0] + 2, width))
        col[: axial.shape[0], : axial.shape[1]] = axial
        col[axial.shape[0] + 2 :, : coronal.shape[1]] = coronal
        grey = (np.clip(col, 0, 1) * 255).astype(np.uint8)
        img = Image.fromarray(grey).resize((width * scale, col.shape[0] * scale), Image.NEAREST)
        canvas = Image.new("L", (img.width + 6, img.height + label), 255)
        canvas.paste(img, (3, label))
        ImageDraw.Draw(canvas).text((4, 3), title, fill=0)
        tiles.append(canvas)
    sheet = Image.new("L", (sum(t.width for t in tiles), tiles[0].height), 255)
    x = 0
    for t in tiles:
        sheet.paste(t, (x, 0))
        x += t.width
    sheet.save(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--picture", default=None)
    args = parser.parse_args()
    cal, cal_h = calibration_volume()
    test, test_h = test_volume()
    weight = best_weight(cal, seed=0)
    print(f"skimage weight chosen on the calibration volume: {weight}")
    cal_rows, *_ = denoise_rows("calibration (example4d)", cal, cal_h, 0, weight)
    test_rows, noisy, ours, ref = denoise_rows("test (MNI152)", test, test_h, 1, weight)
    table(cal_rows + test_rows, f"TV denoising, Gaussian noise sigma {SIGMA}")
    cal_fill, *_ = inpaint_rows("calibration (example4d)", cal, cal_h, 2)
    test_fill, damaged, f_ours, f_ref, _ = inpaint_rows("test (MNI152)", test, test_h, 3)
    table(cal_fill + test_fill, "Inpainting, balls and a two-slice slab missing (PSNR in the hole)")
    if args.picture:
        picture(args.picture, test, noisy, ours, ref, damaged, f_ours, f_ref)
        print(f"\nwrote {args.picture}")


if __name__ == "__main__":
    main()
