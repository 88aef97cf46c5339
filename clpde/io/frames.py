"""Frame sequences in and tracking results out.

Reading: a video file (through io/video.py's reader: pip install "clpde[video]") or a folder
of images (sorted by name, numbers in natural order), one frame at a time (`FrameSource`, the
frames of a film restoration) or all at once (`read_frames`, the tracker's), or a
multi-page TIFF stack. Writing:
one mask PNG per frame, an overlay GIF with the contours drawn on the frames, and the
contours as polygons per frame (JSON). Every file is written atomically, and
`write_tracking` writes a whole result folder so that a failure leaves no partial set of
files behind.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from .images import (
    IMAGE_FORMATS,
    PathLike,
    atomic_output,
    output_folder,
    read_image,
    write_gif,
    write_image,
)
from .video import VideoReader
from .video_probe import FORMATS, READ_SUFFIXES, is_video

TIFF_SUFFIXES = {".tif", ".tiff"}
FOLDER_RATE = Fraction(25)  # a folder of frames states no rate


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


class FrameSource:
    """The frames of a video or of a folder of images, read one at a time, in order.

    Only the frame being read is held: a film of any length streams through it. A folder's
    images are sorted by name with numbers in natural order (`image_files`).

    Parameters
    ----------
    path : str or PathLike
        A video file (.mp4, .mkv, .mov, .avi, ...) or a folder of images (PNG, TIFF, JPEG).

    Attributes
    ----------
    path : Path
        The video or folder.
    count : int
        The number of frames.
    rate : Fraction
        Frames per second (a folder states none: FOLDER_RATE).
    shape : tuple of int
        A frame's shape, (rows, columns) or (rows, columns, channels).
    dtype : numpy.dtype
        The frames' dtype (a video's: uint8, or uint16 for deeper ones).
    reader : VideoReader or None
        A video's reader: its description (``reader.info``) and the timestamps of the frames
        read (``reader.timestamps``).
    files : list of Path or None
        A folder's images.

    Raises
    ------
    InputError
        For a path that does not exist, is neither a video nor a folder, or a folder without
        images; while reading, a frame of another size, kind or dtype than the first.

    Examples
    --------
    >>> for frame in FrameSource("scans/"):  # doctest: +SKIP
    ...     print(frame.shape)
    """

    def __init__(self, path: PathLike) -> None:
        self.path = Path(path)
        self.reader = self.files = None
        if self.path.is_dir():
            self.files = image_files(self.path)
            self.count, self.rate = len(self.files), FOLDER_RATE
            first = read_image(self.files[0])
        elif is_video(self.path):
            self.reader = VideoReader(self.path)
            info = self.reader.info
            self.count, self.rate = info.frames, info.rate
            first = np.zeros((info.height, info.width, 3), info.dtype)
        elif not self.path.exists():
            raise InputError(f"input {self.path} does not exist")
        else:
            raise InputError(
                f"{self.path} is neither a video ({', '.join(sorted(FORMATS))}, ...) "
                "nor a folder of images"
            )
        self.shape, self.dtype = first.shape, first.dtype

    def __len__(self) -> int:
        return self.count

    def __iter__(self) -> Iterator[np.ndarray]:
        if self.reader is not None:
            yield from self.reader
            return
        first = self.files[0].name
        for path in self.files:
            frame = read_image(path)
            if frame.shape[:2] != self.shape[:2]:
                raise InputError(
                    f"{path.name} is {frame.shape[1]}x{frame.shape[0]} but {first} is "
                    f"{self.shape[1]}x{self.shape[0]}; all frames must have one size"
                )
            if frame.shape != self.shape:
                raise InputError(
                    f"{path.name} has shape {frame.shape} but {first} has {self.shape}; "
                    "mixed grey and colour frames: convert them to one kind"
                )
            if frame.dtype != self.dtype:
                raise InputError(
                    f"{path.name} is {frame.dtype} but {first} is {self.dtype}; all "
                    "frames need one type: convert them to one bit depth"
                )
            yield frame


def read_frames(path, grey: bool = True) -> np.ndarray:
    """The frames of a video file, a folder of images or a multi-page TIFF, as (T, H, W)
    (or (T, H, W, C) with grey=False and colour frames), in the file's dtype."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"input {path} does not exist")
    if path.is_dir() or is_video(path):
        frames = np.stack(list(FrameSource(path)))
    elif path.suffix.lower() in TIFF_SUFFIXES:
        frames = _read_tiff_stack(path)
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
    """An RGB uint8 picture of a frame (grey, or colour with its channels last) with the
    mask's boundary pixels in `colour`; the frame's range is stretched to 0..255, over all
    its channels at once so that its colours keep their hue."""
    from scipy import ndimage

    frame = np.asarray(frame, np.float64)
    if frame.ndim == 3:
        frame = frame[..., :3]  # alpha is not shown
    lo, hi = float(frame.min()), float(frame.max())
    scaled = np.zeros_like(frame) if hi <= lo else (frame - lo) / (hi - lo)
    rgb = np.rint(scaled * 255).astype(np.uint8)
    if rgb.ndim == 2:
        rgb = np.repeat(rgb[..., np.newaxis], 3, axis=-1)
    elif rgb.shape[-1] < 3:  # grey with alpha
        rgb = np.repeat(rgb[..., :1], 3, axis=-1)
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
