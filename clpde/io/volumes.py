"""Reading and writing 3D volumes: NIfTI (.nii, .nii.gz; through nibabel, an optional
dependency) and multi-page TIFF (.tif, .tiff; through tifffile).

Volumes come back as (Z, Y, X) arrays, slices first as clpde's volume flows take them, with
a channel axis last for NIfTI's 4th dimension and TIFF's samples (RGB pages): (Z, Y, X, C).
NIfTI stores (X, Y, Z[, C]), so its axes are reversed on the way in and back on the way out.
The file's dtype is kept both ways, and every write is atomic (io/images.py's
atomic_output). `VolumeInfo` carries the spacing (z, y, x) and, for NIfTI, the affine and
header, so a volume read, processed and written keeps its place in the scanner's space.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from .images import PathLike, atomic_output, check_folder_writable

VOLUME_FORMATS = {".nii": "NIfTI", ".nii.gz": "NIfTI", ".tif": "TIFF", ".tiff": "TIFF"}


@dataclass(frozen=True)
class VolumeInfo:
    """What a volume file says besides its voxels.

    Parameters
    ----------
    spacing : tuple of float
        Voxel size along (z, y, x), in the file's units (mm for NIfTI); 1 where unknown.
    affine : ndarray, optional
        NIfTI's 4x4 voxel-to-world matrix (of the file's (x, y, z) voxel indices).
    header : object, optional
        NIfTI's header, reused when the volume is written back (`write_volume(like=...)`).
    """

    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    affine: np.ndarray | None = None
    header: Any = None


def volume_format(path: PathLike) -> str:
    """'NIfTI' or 'TIFF', from the file name's extension."""
    name = Path(path).name.lower()
    for suffix in (".nii.gz", ".nii", ".tiff", ".tif"):
        if name.endswith(suffix):
            return VOLUME_FORMATS[suffix]
    raise InputError(
        f"{path}: unsupported volume format; use a .nii, .nii.gz (NIfTI) or .tif/.tiff "
        "(multi-page TIFF) file"
    )


def is_volume_file(path: PathLike) -> bool:
    """Whether the command line should read `path` as a volume: a NIfTI file, or a TIFF file
    of more than one page (a single-page TIFF is an image)."""
    name = Path(path).name.lower()
    if name.endswith((".nii", ".nii.gz")):
        return True
    if not name.endswith((".tif", ".tiff")) or not Path(path).is_file():
        return False
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            series = tif.series[0]
            return len(series.shape) - ("S" in series.axes) >= 3
    except Exception:  # not a TIFF the volume reader could take: the image reader says why
        return False


def _nibabel():
    try:
        import nibabel
    except ImportError:
        raise InputError(
            "NIfTI files need nibabel, which is not installed: "
            "pip install nibabel (or clpde[nifti])"
        ) from None
    return nibabel


def read_volume(path: PathLike, *, with_info: bool = False):
    """The voxels of a NIfTI or multi-page TIFF file as (Z, Y, X) or (Z, Y, X, C), in the
    file's dtype (NIfTI data with a scaling other than 1, 0 comes back scaled, as floats).

    Parameters
    ----------
    path : str or PathLike
        A .nii, .nii.gz, .tif or .tiff file.
    with_info : bool, optional
        Also return a VolumeInfo (spacing, and NIfTI's affine and header).

    Returns
    -------
    ndarray or (ndarray, VolumeInfo)

    Raises
    ------
    InputError
        For a missing, empty or unreadable file, another format, or a NIfTI file without
        nibabel installed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from clpde.io import read_volume, write_volume
    >>> path = Path(tempfile.mkdtemp()) / "v.tif"
    >>> vol = np.arange(24, dtype=np.uint16).reshape(2, 3, 4)
    >>> back, info = read_volume(write_volume(path, vol, spacing=(3, 1, 1)), with_info=True)
    >>> back.dtype, bool((back == vol).all()), info.spacing
    (dtype('uint16'), True, (3.0, 1.0, 1.0))
    """
    path = Path(path)
    kind = volume_format(path)
    if not path.exists():
        raise InputError(f"input file {path} does not exist")
    if not path.is_file():
        raise InputError(f"input {path} is not a file")
    if path.stat().st_size == 0:
        raise InputError(f"input file {path} is empty (0 bytes); give a volume file")
    reader = _read_nifti if kind == "NIfTI" else _read_tiff
    try:
        volume, info = reader(path)
    except InputError:
        raise
    except Exception as exc:  # the libraries' own errors: one line naming the file
        raise InputError(f"cannot read {path} as {kind}: {exc}") from None
    return (volume, info) if with_info else volume


def _read_nifti(path: Path):
    nib = _nibabel()
    img = nib.load(str(path))
    if len(img.shape) not in (3, 4):
        raise InputError(
            f"{path}: a NIfTI volume has 3 or 4 dimensions (x, y, z[, channels]), this one "
            f"has shape {img.shape}"
        )
    slope, inter = img.dataobj.slope, img.dataobj.inter
    if slope == 1 and inter == 0:
        data = np.asarray(img.dataobj.get_unscaled())  # the stored dtype, not floats
    else:
        data = np.asarray(img.dataobj)
    volume = np.ascontiguousarray(data.transpose((2, 1, 0, 3) if data.ndim == 4 else (2, 1, 0)))
    zooms = tuple(float(z) for z in img.header.get_zooms()[:3])
    info = VolumeInfo(tuple(reversed(zooms)), np.array(img.affine), img.header.copy())
    return volume, info


def _read_tiff(path: Path):
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        axes = series.axes
        volume = series.asarray()
        spacing = _tiff_spacing(tif)
    # samples (RGB pages) last, one page of a plain image as a volume of one slice
    if "S" in axes and axes.index("S") != len(axes) - 1:
        volume = np.moveaxis(volume, axes.index("S"), -1)
        axes = axes.replace("S", "") + "S"
    spatial = len(axes) - ("S" in axes)
    if spatial == 2:
        volume = volume[None]
    elif spatial != 3:
        raise InputError(
            f"{path}: a TIFF volume has pages of one image each (Z, Y, X[, samples]), this "
            f"one has axes {series.axes} of shape {series.shape}"
        )
    return np.ascontiguousarray(volume), VolumeInfo(spacing)


def _tiff_spacing(tif) -> tuple[float, float, float]:
    """(z, y, x) spacing: clpde's own (tifffile's shaped metadata), else ImageJ's, else 1."""
    meta = tif.shaped_metadata[0] if tif.shaped_metadata else None
    if meta and "spacing" in meta and len(meta["spacing"]) == 3:
        return tuple(float(s) for s in meta["spacing"])
    ij = tif.imagej_metadata or {}
    z = float(ij.get("spacing", 1.0))
    page = tif.pages.first
    y = x = 1.0
    if "XResolution" in page.tags and "YResolution" in page.tags:
        xr, yr = (page.tags[t].value for t in ("XResolution", "YResolution"))
        x = xr[1] / xr[0] if xr[0] else 1.0
        y = yr[1] / yr[0] if yr[0] else 1.0
    return (z, y, x)


def write_volume(
    path: PathLike,
    volume: ArrayLike,
    *,
    spacing: ArrayLike | None = None,
    like: VolumeInfo | None = None,
) -> Path:
    """Write a (Z, Y, X) or (Z, Y, X, C) volume to a NIfTI or multi-page TIFF file (by
    extension), atomically, in its own dtype (bool as uint8 in NIfTI, which has no 1-bit
    type).

    Parameters
    ----------
    path : str or PathLike
        A .nii, .nii.gz, .tif or .tiff file name.
    volume : array_like
        The voxels, slices first.
    spacing : array_like, optional
        Voxel size (z, y, x); by default `like`'s, else 1.
    like : VolumeInfo, optional
        What `read_volume(..., with_info=True)` gave for the input: its NIfTI affine and
        header are kept (the dtype and scaling are the array's own).

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    InputError
        For another shape or format, a folder that cannot be written, a dtype the format
        cannot hold, or a NIfTI file without nibabel installed.
    """
    path = Path(path)
    kind = volume_format(path)
    volume = np.asarray(volume)
    if volume.ndim not in (3, 4):
        raise InputError(
            f"{path}: a volume has shape (Z, Y, X) or (Z, Y, X, C), got {volume.shape}"
        )
    if spacing is None:
        spacing = like.spacing if like is not None else (1.0, 1.0, 1.0)
    spacing = np.asarray(spacing, dtype=np.float64).reshape(-1)
    if spacing.shape != (3,) or not np.all(np.isfinite(spacing)) or np.any(spacing <= 0):
        raise InputError(f"spacing must be three positive numbers (z, y, x), got {spacing!r}")
    if path.is_dir():
        raise InputError(f"output {path} is a folder, not a file name")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(f"output folder {folder} does not exist; create it first")
    check_folder_writable(folder, str(path))
    if kind == "NIfTI":
        image = _nifti_image(path, volume, spacing, like)
        with atomic_output(path) as tmp:
            # nibabel chooses compression by the name: keep the real suffix on the temporary
            staged = tmp.with_name(tmp.name + "".join(Path(path.name).suffixes[-2:]))
            try:
                image.to_filename(str(staged))
                staged.replace(tmp)
            finally:
                staged.unlink(missing_ok=True)
        return path
    import tifffile

    if volume.dtype == np.float16 or volume.dtype.kind == "c":
        raise InputError(
            f"{path}: TIFF volumes hold integers, float32/64 or bool, not {volume.dtype}"
        )
    rgb = volume.ndim == 4 and volume.shape[-1] in (3, 4) and volume.dtype != bool
    with atomic_output(path) as tmp:
        tifffile.imwrite(
            tmp,
            volume,
            photometric="rgb" if rgb else "minisblack",
            planarconfig="contig" if volume.ndim == 4 else None,
            extrasamples=("unassalpha",) if rgb and volume.shape[-1] == 4 else None,
            metadata={"axes": "ZYXS" if volume.ndim == 4 else "ZYX", "spacing": spacing.tolist()},
            resolution=(1 / spacing[2], 1 / spacing[1]),
        )
    return path


def _nifti_image(path: Path, volume: np.ndarray, spacing: np.ndarray, like: VolumeInfo | None):
    nib = _nibabel()
    if volume.dtype == bool:
        volume = volume.astype(np.uint8)  # NIfTI has no 1-bit type
    data = volume.transpose((2, 1, 0, 3) if volume.ndim == 4 else (2, 1, 0))
    header = like.header.copy() if like is not None and like.header is not None else None
    affine = like.affine if like is not None and like.affine is not None else None
    if affine is None:
        affine = np.diag([spacing[2], spacing[1], spacing[0], 1.0])
    try:
        # dtype given: nibabel refuses int64 otherwise (NIfTI holds it)
        image = nib.Nifti1Image(data, affine, header, dtype=data.dtype)
    except Exception as exc:
        raise InputError(f"{path}: NIfTI cannot hold this volume: {exc}") from None
    image.set_data_dtype(data.dtype)
    image.header.set_zooms(
        (spacing[2], spacing[1], spacing[0]) + tuple(image.header.get_zooms()[3:])
    )
    # the array is written as it is: no scaling on the way out
    image.header.set_slope_inter(1, 0)
    return image
