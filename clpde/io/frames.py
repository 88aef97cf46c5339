"""Frame sequences in and tracking results out.

Reading: a video file (through io/video.py's reader: pip install "clpde[video]"), a folder
of images (sorted by name, numbers in natural order) or a multi-page TIFF stack. Writing:
one mask PNG per frame, an overlay GIF with the contours drawn on the frames, and the
contours as polygons per frame (JSON). Every file is written atomically, and
`write_tracking` writes a whole result folder so that a failure leaves no partial set of
files behind.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from .images import IMAGE_FORMATS, atomic_output, output_folder, read_image, write_gif, write_image
from .video import READ_SUFFIXES, is_video, read_video

TIFF_SUFFIXES = {".tif", ".tiff"}


def _natural_key(path: Path):
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def to_grey(frames: np.ndarray) -> np.ndarray:
    """(..., H, W, 3|4) colour to (..., H, W) grey (Rec. 601 luma), keeping the dtype."""
    frames = np.asarray(frames)
    luma = frames[..., :3].astype(np.float64) @ np.array([0.299, 0.587, 0.114])
    if np.issubdtype(frames.dtype, np.integer):
        info = np.iinfo(frames.dtype)
        return np.clip(np.rint(luma), info.min, info.max).astype(frames.dtype)
    return luma.astype(frames.dtype)


def _read_tiff_stack(path: Path) -> np.ndarray:
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            pages = len(tif.pages)
            data = tif.asarray(key=range(pages)) if pages > 1 else tif.asarray()
    except Exception as exc:  # noqa: BLE001
        detail = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise InputError(f"cannot read {path} as a TIFF stack: {detail}") from None
    data = np.asarray(data)
    if pages == 1 and data.ndim == 2:
        data = data[np.newaxis]
    elif pages == 1 and data.ndim == 3 and data.shape[-1] in (3, 4):
        data = data[np.newaxis]  # one colour page
    return data


def image_files(folder) -> list[Path]:
    """The images of a folder, sorted by name with numbers in natural order: the frames of a
    sequence (tracking's input, a film's frames or masks)."""
    folder = Path(folder)
    files = sorted(
        (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_FORMATS),
        key=_natural_key,
    )
    if not files:
        raise InputError(
            f"the folder {folder} holds no images (.png, .tif/.tiff, .jpg/.jpeg); put the "
            "frames there, named so that they sort in order (frame_001.png, frame_002.png, ...)"
        )
    return files


def _read_folder(path: Path) -> np.ndarray:
    files = image_files(path)
    frames = [read_image(p) for p in files]
    for p, f in zip(files, frames, strict=False):
        if f.shape[:2] != frames[0].shape[:2]:
            raise InputError(
                f"{p.name} is {f.shape[1]}x{f.shape[0]} but {files[0].name} is "
                f"{frames[0].shape[1]}x{frames[0].shape[0]}; all frames must have one size"
            )
        if f.shape != frames[0].shape:
            raise InputError(
                f"{p.name} has shape {f.shape} but {files[0].name} has {frames[0].shape}; "
                "mixed grey and colour frames: convert them to one kind"
            )
    return np.stack(frames)


def read_frames(path, grey: bool = True) -> np.ndarray:
    """The frames of a video file, a folder of images or a multi-page TIFF, as (T, H, W)
    (or (T, H, W, C) with grey=False and colour frames), in the file's dtype."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"input {path} does not exist")
    if path.is_dir():
        frames = _read_folder(path)
    elif path.suffix.lower() in TIFF_SUFFIXES:
        frames = _read_tiff_stack(path)
    elif is_video(path):
        frames = read_video(path)[0]
    else:
        raise InputError(
            f"{path}: unsupported input {path.suffix or '(no extension)'!r}; give a video "
            f"({', '.join(sorted(READ_SUFFIXES))}), a multi-page .tif or a folder of images"
        )
    if frames.dtype == bool:
        frames = frames.astype(np.uint8) * 255
    if frames.ndim == 4:
        if frames.shape[-1] == 1:
            frames = frames[..., 0]
        elif grey:
            frames = to_grey(frames)
    if frames.ndim not in (3, 4) or frames.shape[0] == 0:
        raise InputError(f"{path} gave frames of shape {frames.shape}; expected (T, H, W)")
    return frames


# ---- results ---------------------------------------------------------------------------


def contour_polygons(mask) -> list[list[list[float]]]:
    """The boundaries of a boolean mask as closed polygons of (x, y) points, sub-pixel
    (half-way between inside and outside pixels)."""
    from skimage.measure import find_contours

    padded = np.pad(np.asarray(mask, np.float64), 1)
    return [
        [[round(float(x) - 1, 3), round(float(y) - 1, 3)] for y, x in poly]
        for poly in find_contours(padded, 0.5)
    ]


def overlay(frame, mask, colour=(255, 40, 40)) -> np.ndarray:
    """An RGB uint8 picture of a grey frame with the mask's boundary pixels in `colour`."""
    from scipy import ndimage

    frame = np.asarray(frame, np.float64)
    lo, hi = float(frame.min()), float(frame.max())
    grey = np.zeros_like(frame) if hi <= lo else (frame - lo) / (hi - lo)
    rgb = np.repeat(np.rint(grey * 255).astype(np.uint8)[..., np.newaxis], 3, axis=-1)
    mask = np.asarray(mask, bool)
    edge = mask & ~ndimage.binary_erosion(mask, border_value=1)
    rgb[edge] = colour
    return rgb


def write_tracking(
    outdir, frames, masks, *, gif: bool = True, duration: float = 0.1, overwrite: bool = False
) -> list[Path]:
    """Write mask_0000.png..., overlay.gif and contours.json into the folder `outdir`.

    The folder is created if missing; an existing one must be empty, or with overwrite=True
    hold only clpde's kinds of output files: it is then replaced as a whole (see
    clpde.io.output_folder), so it holds this run's files only. Everything is written into a
    temporary folder beside `outdir` first, so a failure leaves `outdir` as it was.
    """
    masks = np.asarray(masks, bool)
    names = []
    with output_folder(outdir, overwrite) as staging:
        for t, mask in enumerate(masks):
            name = f"mask_{t:04d}.png"
            write_image(staging / name, mask.astype(np.uint8) * 255)
            names.append(name)
        polygons = {
            "frames": [{"index": t, "polygons": contour_polygons(m)} for t, m in enumerate(masks)],
            "shape": list(masks.shape[1:]),
            "coordinates": "x, y in pixels",
        }
        with atomic_output(staging / "contours.json") as tmp:
            tmp.write_text(json.dumps(polygons))
        names.append("contours.json")
        if gif:
            write_gif(
                staging / "overlay.gif",
                [overlay(f, m) for f, m in zip(frames, masks, strict=False)],
                duration=duration,
            )
            names.append("overlay.gif")
    return [Path(outdir) / n for n in names]
