"""A damaged photo for trying inpainting: scikit-image's astronaut with a caption, a date
and scratches painted over it. Needs only clpde's own dependencies (Pillow draws the text).
Used by `clpde inpaint --demo` and examples/inpaint_demo.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def damage_mask(shape, seed: int = 3, text: bool = True, scratches: bool = True) -> np.ndarray:
    """Text and thin scratches (about 8% of the pixels) for an image of `shape` (rows, cols)."""
    from PIL import Image, ImageDraw, ImageFont

    ny, nx = shape
    canvas = Image.new("L", (nx, ny), 0)
    draw = ImageDraw.Draw(canvas)
    size = max(12, nx // 13)
    font = ImageFont.load_default(size=size)
    lines = ["Summer 1984", "Houston, TX", "do not copy", "25.12.1984"]
    for k, line in enumerate(lines if text else []):
        draw.text((nx // 20 + (k % 2) * nx // 6, ny // 10 + k * ny // 4.4), line, fill=255,
                  font=font, stroke_width=max(1, size // 16), stroke_fill=255)
    rng = np.random.default_rng(seed)
    for _ in range(6 if scratches else 0):  # scratches: gently curved, 1-2 pixels wide
        x0, y0 = rng.uniform(0, nx), rng.uniform(0, ny)
        angle = rng.uniform(0, np.pi)
        t = np.linspace(-0.35, 0.35, 30) * nx
        bend = rng.uniform(-0.2, 0.2) * t**2 / nx
        xs = x0 + t * np.cos(angle) - bend * np.sin(angle)
        ys = y0 + t * np.sin(angle) + bend * np.cos(angle)
        draw.line(list(zip(xs, ys)), fill=255, width=int(rng.integers(1, 3)))
    return np.asarray(canvas) > 0


def demo_case():
    """(original, damaged, mask): a uint8 RGB photo, the same with white damage, the mask."""
    from skimage import data

    original = data.astronaut()
    mask = damage_mask(original.shape[:2])
    damaged = original.copy()
    damaged[mask] = 255
    return original, damaged, mask


def side_by_side(*images, gap: int = 6) -> np.ndarray:
    """Images of one height in a row, separated by white gaps (greyscale made RGB)."""
    rgb = [np.repeat(i[..., None], 3, -1) if i.ndim == 2 else i[..., :3] for i in images]
    spacer = np.full((rgb[0].shape[0], gap, 3), 255, np.uint8)
    parts = []
    for image in rgb:
        parts += [image, spacer]
    return np.concatenate(parts[:-1], axis=1)


def run_demo(outdir, device=None, progress=None, overwrite=False) -> list[Path]:
    """Damage the photo, inpaint it and write the PNGs into the folder `outdir`; returns the
    paths. The folder is created if missing; an existing one must be empty, or with
    overwrite=True hold only clpde's kinds of output files (clpde.io.output_folder)."""
    from . import inpaint
    from .io import check_output_folder, output_folder, write_image

    outdir = Path(outdir)
    check_output_folder(outdir, overwrite)
    original, damaged, mask = demo_case()
    restored, info = inpaint(damaged, mask, channel_axis=-1, device=device, progress=progress,
                             return_info=True)
    written = []
    with output_folder(outdir, overwrite) as staging:
        for name, image in (("original.png", original), ("damaged.png", damaged),
                            ("mask.png", mask.astype(np.uint8) * 255), ("inpainted.png", restored),
                            ("inpaint_before_after.png", side_by_side(damaged, restored))):
            write_image(staging / name, image)
            written.append(outdir / name)
    peers = ", ".join(f"{name} {value:.1f} dB" for name, value in peer_psnr(damaged, mask, original).items())
    print(f"inpainted {mask.sum()} pixels ({100 * mask.mean():.1f}%) in {info.steps} steps, "
          f"{info.seconds:.1f} s; PSNR inside the mask {psnr_in_mask(restored, original, mask):.1f} "
          f"dB (higher is closer to the original; on the same damage: {peers})")
    return written


def psnr_in_mask(restored, original, mask) -> float:
    """PSNR (dB) of the restored pixels inside the mask, for 8-bit images."""
    diff = restored[mask].astype(np.float64) - original[mask]
    return float(10 * np.log10(255**2 / max(np.mean(diff**2), 1e-12)))


def peer_psnr(damaged, mask, original) -> dict:
    """PSNR inside the mask of the peers installed here, on the same 8-bit colour damage:
    scikit-image's biharmonic fill (a clpde dependency) and, when OpenCV is installed, its
    Telea and Navier-Stokes methods (radius 3). A figure of merit with something beside it."""
    from skimage.restoration import inpaint_biharmonic

    fills = {"scikit-image biharmonic": lambda: np.clip(np.rint(
        255 * inpaint_biharmonic(damaged, mask, channel_axis=-1)), 0, 255).astype(np.uint8)}
    try:
        import cv2
    except ImportError:
        pass
    else:
        m = mask.astype(np.uint8)
        fills["OpenCV Telea"] = lambda: cv2.inpaint(damaged, m, 3, cv2.INPAINT_TELEA)
        fills["OpenCV Navier-Stokes"] = lambda: cv2.inpaint(damaged, m, 3, cv2.INPAINT_NS)
    return {name: psnr_in_mask(fill(), original, mask) for name, fill in fills.items()}
