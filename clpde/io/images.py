"""Reading and writing image files: PNG, TIFF and JPEG images, and animated GIFs.

Every write is atomic: the data goes to a temporary file in the destination's folder and
is renamed over the destination only once it is complete, so a failed or interrupted run
never leaves a half-written or stray file behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from ..errors import InputError
from ..imagedata import mask_plane

PathLike = str | os.PathLike

IMAGE_FORMATS = {".png": "PNG", ".tif": "TIFF", ".tiff": "TIFF", ".jpg": "JPEG", ".jpeg": "JPEG"}


def image_format(path: PathLike) -> str:
    """'PNG', 'TIFF' or 'JPEG', from the file name's extension."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMAGE_FORMATS:
        raise InputError(
            f"{path}: unsupported image format {suffix or '(no extension)'!r}; "
            "use a .png, .tif/.tiff or .jpg/.jpeg file"
        )
    return IMAGE_FORMATS[suffix]


def read_image(path: PathLike) -> np.ndarray:
    """The pixels of a PNG, TIFF or JPEG file, in the file's own dtype.

    Greyscale images come back as (rows, columns), colour ones as (rows, columns, channels).
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"input file {path} does not exist")
    if not path.is_file():
        raise InputError(f"input {path} is not a file")
    kind = image_format(path)
    if path.stat().st_size == 0:
        raise InputError(f"input file {path} is empty (0 bytes); give an image file")
    try:
        if kind == "TIFF":
            import tifffile

            image = tifffile.imread(path)
        elif kind == "PNG" and _png_bit_depth(path) == 16:
            # Pillow reads 16-bit colour PNGs as 8-bit: libpng's decoder keeps the 16 bits.
            import imagecodecs

            image = imagecodecs.png_decode(path.read_bytes())
        else:
            import imageio.v3 as iio

            with _no_pixel_limit():
                image = iio.imread(path, plugin="pillow", extension=path.suffix.lower())
    except MemoryError:
        raise InputError(
            f"{path} is too large to read into this computer's memory; crop or downscale it first"
        ) from None
    except Exception as exc:  # noqa: BLE001  (readers raise many types: all mean unreadable)
        detail = (str(exc).strip().splitlines() or [type(exc).__name__])[0].rstrip(".")
        # imageio's "`pillow` can not handle the given uri" names its plugin, not the file's
        # problem: only the readers' own words (such as "image file is truncated") are kept.
        detail = "" if "can not handle" in detail or "cannot identify" in detail else f" ({detail})"
        raise InputError(
            f"cannot read {path}: not a {kind} image, or a damaged one{detail}; clpde reads "
            ".png, .tif/.tiff and .jpg/.jpeg image files"
        ) from None
    return np.asarray(image)


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_bit_depth(path: Path) -> int | None:
    """The bit depth in a PNG file's header (its IHDR chunk comes first), None if not a PNG."""
    with open(path, "rb") as f:
        head = f.read(26)
    if len(head) < 26 or not head.startswith(_PNG_SIGNATURE) or head[12:16] != b"IHDR":
        return None
    return head[24]


@contextlib.contextmanager
def _no_pixel_limit():
    """Lift Pillow's decompression-bomb limit (about 179 million pixels) while reading: it
    guards servers against untrusted uploads, while clpde reads the local files its user
    names, such as a 20000x20000 scan."""
    from PIL import Image

    limit = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = None
    try:
        yield
    finally:
        Image.MAX_IMAGE_PIXELS = limit


def check_folder_writable(folder: PathLike, what: str) -> None:
    """Raise InputError unless a file can be created in `folder` (`what` names the output
    in the message). A file is made and removed, since permission bits alone do not tell:
    root ignores them, while a read-only mount, an immutable folder or sysfs refuse root."""
    folder = Path(folder) if str(folder) else Path(".")
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".clpde-", suffix=".part")
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(
            f"cannot write {what}: the folder {folder} is not writable ({reason}); "
            "choose a folder you can write to"
        ) from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)


def check_output_file(path: PathLike) -> Path:
    """Raise InputError, before any work, unless `path` can be written as an image file:
    a known extension, not a folder, in an existing folder that can be written to."""
    path = Path(path)
    image_format(path)
    if path.is_dir():
        raise InputError(f"output {path} is a folder, not a file name")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(f"output folder {folder} does not exist; create it first")
    check_folder_writable(folder, str(path))
    return path


def check_writable(path: PathLike, dtype: DTypeLike, shape: Sequence[int]) -> None:
    """Raise InputError, before any work is done, if `path` cannot hold such an image."""
    path = Path(path)
    kind = image_format(path)
    dtype = np.dtype(dtype)
    shape = tuple(shape)
    channels = 1 if len(shape) == 2 else shape[-1] if len(shape) == 3 else None
    if channels is None or channels > 4:
        raise InputError(
            f"{path}: cannot write an array of shape {shape} as an image; expected "
            "(rows, columns) or (rows, columns, channels) with at most 4 channels"
        )
    if kind == "JPEG" and (dtype != np.uint8 or channels not in (1, 3)):
        png = dtype.kind == "u" and dtype.itemsize <= 2 or (dtype.kind == "b" and channels == 1)
        raise InputError(
            f"{path}: JPEG stores 8-bit greyscale or RGB only, not {dtype} with {channels} "
            f"channel(s); write a {'.png or .tif' if png else '.tif'} file instead"
        )
    if kind == "PNG":
        if dtype not in (np.dtype(np.uint8), np.dtype(np.uint16), np.dtype(bool)):
            raise InputError(
                f"{path}: PNG stores 8- or 16-bit integers, not {dtype}; write a .tif file "
                "to keep the values exactly"
            )
        if dtype.kind == "b" and channels != 1:
            raise InputError(
                f"{path}: PNG stores 1-bit images as greyscale only, not {channels} bool "
                "channels; convert with image.astype(np.uint8) * 255, or write a .tif file"
            )
    check_output_file(path)


@contextlib.contextmanager
def atomic_output(path: PathLike) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success it replaces `path`, else it is removed."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp_name = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".part")
    except OSError as exc:  # name the folder, not the temporary file that was never made
        raise InputError(f"cannot write {path}: {exc.strerror} in folder {folder}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp makes the file private (0600); give it the mode a plain open() would.
        os.chmod(tmp, _default_file_mode(path))
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def write_bytes(path: PathLike, data: bytes) -> Path:
    """Write `data` to the file `path`, atomically (see atomic_output)."""
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_bytes(data)
    return path


def _default_file_mode(path: Path) -> int:
    if path.exists():
        return path.stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def write_image(path: PathLike, array: ArrayLike) -> Path:
    """Write `array` to a PNG, TIFF or JPEG file (chosen by extension), atomically.

    The dtype is kept as the format allows: PNG holds uint8 and uint16 (1 to 4 channels) and
    1-bit greyscale (bool), JPEG 8-bit greyscale or RGB, TIFF any integer, float or bool
    dtype.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from clpde.io import read_image, write_image
    >>> folder = Path(tempfile.mkdtemp())
    >>> ramp = np.arange(0, 65536, 4369, dtype=np.uint16).reshape(4, 4)
    >>> path = write_image(folder / "ramp.png", ramp)
    >>> back = read_image(path)
    >>> back.dtype, bool((back == ramp).all())
    (dtype('uint16'), True)
    """
    path = Path(path)
    array = np.asarray(array)
    check_writable(path, array.dtype, array.shape)
    kind = image_format(path)
    with atomic_output(path) as tmp:
        if kind == "TIFF":
            import tifffile

            # RGB photometry packs bool samples into bits wrongly: bool stays greyscale samples.
            rgb = array.ndim == 3 and array.shape[-1] in (3, 4) and array.dtype != bool
            extra = ("unassalpha",) if rgb and array.shape[-1] == 4 else None
            tifffile.imwrite(
                tmp, array, photometric="rgb" if rgb else "minisblack", extrasamples=extra
            )
        elif kind == "PNG" and array.dtype == np.uint16 and array.ndim == 3 and array.shape[-1] > 1:
            # Pillow cannot write 16-bit colour: libpng's encoder, at zlib level 1 as below.
            import imagecodecs

            tmp.write_bytes(imagecodecs.png_encode(np.ascontiguousarray(array), level=1))
        else:
            import imageio.v3 as iio

            if array.ndim == 3 and array.shape[-1] == 1:
                array = array[..., 0]
            # zlib level 1 for PNG, as OpenCV's imwrite: much faster than Pillow's 6 for
            # slightly larger files, lossless either way (measured in docs/batch.md).
            options = {"JPEG": {"quality": 95}, "PNG": {"compress_level": 1}}.get(kind, {})
            iio.imwrite(tmp, array, plugin="pillow", extension=path.suffix.lower(), **options)
    return path


def _frame_to_uint8(frame) -> np.ndarray:
    """GIF frames are 8-bit: integers scale by their dtype's range, floats are taken in [0, 1]."""
    frame = np.asarray(frame)
    if frame.dtype == np.uint8:
        return frame
    if frame.dtype == bool:
        return frame.astype(np.uint8) * 255
    if np.issubdtype(frame.dtype, np.integer):
        info = np.iinfo(frame.dtype)
        scaled = (frame.astype(np.float64) - info.min) / (float(info.max) - info.min)
    elif np.issubdtype(frame.dtype, np.floating):
        if not np.isfinite(frame).all():
            raise InputError("a GIF frame contains NaN or infinite values")
        scaled = np.clip(frame, 0.0, 1.0)
    else:
        raise InputError(f"GIF frames must be integer, bool or float arrays, not {frame.dtype}")
    return np.rint(scaled * 255).astype(np.uint8)


def write_gif(
    path: PathLike, frames: Iterable[ArrayLike], duration: float = 0.1, loop: int = 0
) -> Path:
    """Write an animated GIF atomically.

    frames: a sequence of (rows, columns) or (rows, columns, 3|4) arrays of one shape;
    uint8 is written as is, other integer dtypes are scaled by their range, floats are
    taken in [0, 1]. duration: seconds each frame is shown. loop: 0 repeats forever.
    """
    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise InputError(f"{path}: an animation must be written to a .gif file")
    frames = [_frame_to_uint8(f) for f in frames]
    if not frames:
        raise InputError("write_gif needs at least one frame")
    shapes = {f.shape for f in frames}
    if len(shapes) != 1:
        raise InputError(f"all GIF frames must have one shape, got {sorted(shapes)}")
    shape = frames[0].shape
    if not (len(shape) == 2 or (len(shape) == 3 and shape[-1] in (3, 4))):
        raise InputError(f"GIF frames must be (rows, columns[, 3|4]) arrays, not shape {shape}")
    duration = float(duration)
    if not np.isfinite(duration) or duration <= 0:
        raise InputError(f"duration must be a positive number of seconds, not {duration}")
    if not path.parent.is_dir():
        raise InputError(f"output folder {path.parent} does not exist; create it first")
    import imageio.v3 as iio

    with atomic_output(path) as tmp:
        iio.imwrite(
            tmp,
            np.stack(frames),
            plugin="pillow",
            extension=".gif",
            duration=round(duration * 1000),
            loop=int(loop),
        )
    return path


def check_not_overwriting_input(inputs: PathLike | Iterable[PathLike], output: PathLike) -> None:
    """Refuse an output path that names (or links to) one of the inputs."""
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    out = Path(output)
    out_resolved = out.resolve()
    for item in inputs:
        src = Path(item)
        same = src.resolve() == out_resolved
        if not same and src.exists() and out.exists():
            same = os.path.samefile(src, out)  # hard links and other aliases
        if same:
            raise InputError(
                f"output {out} is the input file {src}; clpde never overwrites its inputs, "
                "choose another output file name"
            )


# ---- output folders ---------------------------------------------------------------------
# What clpde writes into output folders; a folder holding anything else is never replaced.
OUTPUT_SUFFIXES = {
    ".png",
    ".gif",
    ".json",
    ".ply",
    ".glb",
    ".tif",
    ".tiff",
    ".jpg",
    ".jpeg",
    ".mp4",
}


def check_output_folder(
    outdir: PathLike, overwrite: bool = False, *, option: str = "overwrite=True"
) -> Path:
    """Refuse, before any work, an output folder that a run could not replace as a whole.

    The rule of every command that writes a folder: the folder is created if missing (its
    parent must exist); an existing one must be empty, unless `overwrite`, which replaces
    the whole folder, and only if it holds nothing but files of the kinds clpde writes
    (OUTPUT_SUFFIXES), so that a run's folder holds that run's outputs only. `option` names
    the way to ask for overwriting in the caller's interface (e.g. '--overwrite').
    """
    outdir = Path(outdir)
    parent = outdir.parent if str(outdir.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(
            f"the folder {parent} for the output {outdir} does not exist; create it first"
        )
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"output {outdir} exists and is not a folder; choose a folder name")
    # the run is staged beside the folder and renamed in: the parent is written to
    check_folder_writable(parent, f"the output folder {outdir}")
    if not outdir.exists():
        return outdir
    entries = sorted(outdir.iterdir())
    if not entries:
        return outdir
    if not overwrite:
        raise InputError(
            f"output folder {outdir} is not empty ({len(entries)} entries); choose a new "
            f"folder, or give {option} to replace its contents"
        )
    foreign = [
        e.name for e in entries if not e.is_file() or e.suffix.lower() not in OUTPUT_SUFFIXES
    ]
    if foreign:
        raise InputError(
            f"output folder {outdir} holds {foreign[0]!r}, which clpde does not write, so it "
            f"will not replace the folder even with {option}; choose another folder"
        )
    return outdir


@contextlib.contextmanager
def output_folder(
    outdir: PathLike, overwrite: bool = False, *, option: str = "overwrite=True"
) -> Iterator[Path]:
    """Yield an empty staging folder beside `outdir`; on success it becomes `outdir` (the old
    folder, if any, is removed as a unit); on failure it is removed and `outdir` is left as
    it was. See check_output_folder for the rule."""
    outdir = check_output_folder(outdir, overwrite, option=option)
    parent = outdir.parent if str(outdir.parent) else Path(".")
    staging = Path(tempfile.mkdtemp(dir=parent, prefix=f".{outdir.name}.", suffix=".part"))
    try:
        yield staging
        replace_folder(staging, outdir)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def replace_folder(staging: Path, final: Path) -> None:
    """Put the finished folder `staging` in place of `final` (which may exist), so that a
    reader sees the old folder or the new one, never a mixture."""
    os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700 folders
    if final.exists():
        # rename(2) may replace an empty folder: move the old one aside into an empty
        # temporary name, put the new one in place, then delete the old one
        old = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.", suffix=".old"))
        os.replace(final, old)
        os.replace(staging, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staging, final)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# ---- masks ------------------------------------------------------------------------------
LOSSY_FORMATS = ("JPEG",)
MASK_RULE = (
    "a pixel is inside where it is brighter than the mask's darkest value, soft "
    "(anti-aliased) edges included; colour masks count by their brightest channel; alpha "
    "is ignored; JPEG masks are cut half-way between their darkest and brightest values"
)


def read_mask(
    path: PathLike,
    shape: Sequence[int] | None = None,
    *,
    what: str = "the image",
    fix: str = "give a mask of the same size",
) -> np.ndarray:
    """A mask image file as a boolean array: True where the mask is bright.

    The rule of clpde.inpaint's arrays (nonzero = inside; colour by the brightest colour
    channel, alpha ignored: clpde.imagedata.mask_plane), with the file's darkest value as
    its zero: every pixel brighter than that is inside, so the grey, anti-aliased rim of
    drawn letters is filled with them (a uniform nonzero mask is all inside). A mask with
    more than two levels gets a warning that says so. A lossy file (JPEG) is cut half-way
    between its darkest and brightest values instead, since its compression rings grey
    around every edge, with a warning. `shape` (rows, columns), if given, is the size it
    must have; `what` names the image it must match in the error, and `fix` the way out.
    """
    import warnings

    path = Path(path)
    mask = mask_plane(read_image(path))
    if shape is not None and mask.shape != tuple(shape):
        verb = "are" if what.endswith("s") else "is"
        raise InputError(
            f"the mask {path} is {mask.shape[1]}x{mask.shape[0]} pixels but "
            f"{what} {verb} {shape[1]}x{shape[0]}; {fix}"
        )
    if mask.dtype == bool:
        return mask.copy()
    if np.issubdtype(mask.dtype, np.floating) and not np.isfinite(mask).all():
        raise InputError(f"the mask {path} contains NaN or infinite values; save it as a 0/255 PNG")
    lo, hi = mask.min(), mask.max()
    if lo == hi:
        return np.full(mask.shape, hi != 0)
    if image_format(path) in LOSSY_FORMATS:
        cut = (float(lo) + float(hi)) / 2
        warnings.warn(
            f"the mask {path} is a lossy {image_format(path)} file, whose edges "
            f"come out grey; read as inside above {cut:g} (half-way between its "
            f"darkest and brightest values), which may leave the damage's rim: grow the "
            f"mask by a pixel (--grow 1), and save masks as PNG",
            stacklevel=2,
        )
        return mask > cut
    levels = len(np.unique(mask))
    if levels > 2:
        warnings.warn(
            f"the mask {path} has {levels} grey levels, not two (soft, anti-aliased "
            f"edges?): every pixel brighter than its darkest value {lo:g} is inside, the "
            f"soft edges included",
            stacklevel=2,
        )
    return mask > lo
