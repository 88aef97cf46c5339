"""`clpde inpaint --demo`: inpaint clpde.data's damaged astronaut and write the pictures,
with the PSNR of clpde's fill beside its peers' on the same damage."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data import damaged_astronaut
from ..inpainting.api import inpaint
from ..io.images import check_output_folder, output_folder, write_image


def side_by_side(*images: np.ndarray, gap: int = 6) -> np.ndarray:
    """Images of one height in a row, separated by white gaps (greyscale made RGB)."""
    rgb = [np.repeat(i[..., None], 3, -1) if i.ndim == 2 else i[..., :3] for i in images]
    spacer = np.full((rgb[0].shape[0], gap, 3), 255, np.uint8)
    parts = []
    for image in rgb:
        parts += [image, spacer]
    return np.concatenate(parts[:-1], axis=1)


def run_demo(outdir, device=None, progress=None, overwrite: bool = False) -> list[Path]:
    """Damage the photo, inpaint it and write the PNGs into the folder `outdir`; returns the
    paths. The folder is created if missing; an existing one must be empty, or with
    overwrite=True hold only clpde's kinds of output files (clpde.io.output_folder)."""

    outdir = Path(outdir)
    check_output_folder(outdir, overwrite)
    original, damaged, mask = damaged_astronaut()
    restored, info = inpaint(
        damaged, mask, channel_axis=-1, device=device, progress=progress, return_info=True
    )
    written = []
    with output_folder(outdir, overwrite) as staging:
        for name, image in (
            ("original.png", original),
            ("damaged.png", damaged),
            ("mask.png", mask.astype(np.uint8) * 255),
            ("inpainted.png", restored),
            ("inpaint_before_after.png", side_by_side(damaged, restored)),
        ):
            write_image(staging / name, image)
            written.append(outdir / name)
    peers = ", ".join(
        f"{name} {value:.1f} dB" for name, value in peer_psnr(damaged, mask, original).items()
    )
    steps = f"{info.steps} steps, " if info.method == "transport" else ""
    print(
        f"inpainted {mask.sum()} pixels ({100 * mask.mean():.1f}%) by {info.method}, {steps}"
        f"{info.seconds:.1f} s; PSNR inside the mask "
        f"{psnr_in_mask(restored, original, mask):.1f} "
        f"dB (higher is closer to the original; on the same damage: {peers})"
    )
    return written


def psnr_in_mask(restored: np.ndarray, original: np.ndarray, mask: np.ndarray) -> float:
    """PSNR (dB) of the restored pixels inside the mask, for 8-bit images."""
    diff = restored[mask].astype(np.float64) - original[mask]
    return float(10 * np.log10(255**2 / max(np.mean(diff**2), 1e-12)))


def peer_psnr(damaged: np.ndarray, mask: np.ndarray, original: np.ndarray) -> dict[str, float]:
    """PSNR inside the mask of the peers installed here, on the same 8-bit colour damage:
    scikit-image's biharmonic fill (a clpde dependency) and, when OpenCV is installed, its
    Telea and Navier-Stokes methods (radius 3). A figure of merit with something beside it."""
    from skimage.restoration import inpaint_biharmonic

    fills = {
        "scikit-image biharmonic": lambda: np.clip(
            np.rint(255 * inpaint_biharmonic(damaged, mask, channel_axis=-1)), 0, 255
        ).astype(np.uint8)
    }
    try:
        import cv2
    except ImportError:
        pass
    else:
        m = mask.astype(np.uint8)
        fills["OpenCV Telea"] = lambda: cv2.inpaint(damaged, m, 3, cv2.INPAINT_TELEA)
        fills["OpenCV Navier-Stokes"] = lambda: cv2.inpaint(damaged, m, 3, cv2.INPAINT_NS)
    return {name: psnr_in_mask(fill(), original, mask) for name, fill in fills.items()}
