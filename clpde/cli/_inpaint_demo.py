"""`clpde inpaint --demo`: inpaint clpde.data's damaged astronaut and write the pictures,
with the PSNR of clpde's fill beside its peers' on the same damage."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data import damaged_astronaut
from ..errors import InputError
from ..inpainting.api import inpaint
from ..io.images import check_folder_writable, check_output_folder, output_folder, write_image


def side_by_side(*images: np.ndarray, gap: int = 6) -> np.ndarray:
    """Images of one height in a row, separated by white gaps (greyscale made RGB)."""
    rgb = [np.repeat(i[..., None], 3, -1) if i.ndim == 2 else i[..., :3] for i in images]
    spacer = np.full((rgb[0].shape[0], gap, 3), 255, np.uint8)
    parts = []
    for image in rgb:
        parts += [image, spacer]
    return np.concatenate(parts[:-1], axis=1)


DEMO_FOLDER = "inpaint_demo"  # the demo's own folder inside the output folder
DEMO_FILES = (
    "original.png",
    "damaged.png",
    "mask.png",
    "inpainted.png",
    "inpaint_before_after.png",
)


def check_demo_output(outdir, overwrite: bool = False) -> Path:
    """The folder the demo writes, `outdir`/inpaint_demo, checked before any work.

    `outdir` is created if missing (its parent must exist). The demo's folder follows
    clpde.io.check_output_folder's rule, except that a folder holding only the demo's own
    files (an earlier run's, from `clpde inpaint --demo` or examples/inpaint_demo.py alike)
    is replaced without being asked."""
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"output {outdir} exists and is not a folder; choose a folder name")
    folder = outdir / DEMO_FOLDER
    if not outdir.exists():
        parent = outdir.parent if str(outdir.parent) else Path(".")
        if not parent.is_dir():
            raise InputError(
                f"the folder {parent} for the output {outdir} does not exist; create it first"
            )
        check_folder_writable(parent, f"the output folder {outdir}")
        return folder
    check_output_folder(folder, overwrite or _holds_only_the_demo(folder), option="--overwrite")
    return folder


def _holds_only_the_demo(folder: Path) -> bool:
    return folder.is_dir() and all(e.is_file() and e.name in DEMO_FILES for e in folder.iterdir())


def run_demo(outdir, device=None, progress=None, overwrite: bool = False) -> list[Path]:
    """Damage the photo, inpaint it and write the PNGs into `outdir`/inpaint_demo; returns
    the paths. `outdir` is created if missing; the rule for the demo's folder is
    check_demo_output's (a rerun replaces its own files; anything else needs overwrite=True,
    and then clpde.io.output_folder's rule)."""

    folder = check_demo_output(outdir, overwrite)
    original, damaged, mask = damaged_astronaut()
    restored, info = inpaint(
        damaged, mask, channel_axis=-1, device=device, progress=progress, return_info=True
    )
    pictures = (original, damaged, mask.astype(np.uint8) * 255, restored)
    pictures += (side_by_side(damaged, restored),)
    Path(outdir).mkdir(exist_ok=True)  # only now: an interrupted run leaves nothing behind
    own = overwrite or _holds_only_the_demo(folder)
    written = []
    with output_folder(folder, own, option="--overwrite") as staging:
        for name, image in zip(DEMO_FILES, pictures, strict=True):
            write_image(staging / name, image)
            written.append(folder / name)
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
