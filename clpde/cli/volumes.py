"""The command line's volumes: `clpde denoise`, `clpde diffuse` and `clpde inpaint` given a
NIfTI file (.nii, .nii.gz) or a TIFF of several pages run clpde.volumes on it, with the
file's voxel spacing, and write a volume of the same format, dtype and (NIfTI) affine."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import InputError
from ..io.images import check_not_overwriting_input
from ..io.volumes import read_volume, volume_format, write_volume
from ..planar.flows import diffuse
from ..planar.rof import denoise_tv
from ..volumes import inpaint_volume
from ._common import show_progress


def _read(path):
    volume, info = read_volume(path, with_info=True)
    return volume, info, (-1 if volume.ndim == 4 else None)


def _check_output(args) -> None:
    volume_format(args.output)  # a volume's extension, refused in one line otherwise
    check_not_overwriting_input(args.input, args.output)


def _done(path, volume, info, what: str) -> int:
    write_volume(path, volume, like=info)
    print(f"{what}: wrote {path} ({' x '.join(map(str, volume.shape))})", file=sys.stderr)
    return 0


def run_volume_denoise(args) -> int:
    """`clpde denoise VOLUME OUT`: TV denoising with the file's spacing."""
    if args.method != "primal-dual" or args.eps is not None:
        raise InputError("volumes are denoised by --method primal-dual only; leave out --eps")
    _check_output(args)
    volume, info, axis = _read(args.input)
    out = denoise_tv(
        volume, sigma=args.sigma, weight=args.weight, channel_axis=axis, spacing=info.spacing,
        device=args.device, max_steps=args.max_steps, vectorial=False if args.per_channel else None,
        progress=show_progress(),
    )  # fmt: skip
    return _done(args.output, out, info, "denoise (volume)")


def run_volume_diffuse(args, flow: str, params: dict) -> int:
    """`clpde diffuse VOLUME OUT --flow ...`: a 3D flow with the file's spacing."""
    _check_output(args)
    volume, info, axis = _read(args.input)
    out = diffuse(
        volume, flow, steps=args.steps, dt=args.dt, channel_axis=axis, device=args.device,
        spacing=info.spacing, progress=show_progress(), **params,
    )  # fmt: skip
    return _done(args.output, out, info, f"diffuse {flow} (volume)")


def run_volume_inpaint(args) -> int:
    """`clpde inpaint VOLUME MASK -o OUT`: the biharmonic fill (or --method spectral, the 3D
    blocks' model), the mask a volume too."""
    if args.method not in (None, "auto", "spectral"):
        raise InputError(
            "volumes are filled by the biharmonic fill (the default) or --method spectral; "
            f"leave out --method {args.method}"
        )
    method = "spectral" if args.method == "spectral" else "biharmonic"
    if args.gif or args.overwrite:
        raise InputError("a volume's fill takes no --gif or --overwrite; leave them out")
    _check_output(args)
    volume, info, axis = _read(args.input)
    mask = read_volume(args.mask)
    if mask.ndim == 4:  # a colour mask: by its brightest channel
        mask = mask.max(axis=-1)
    out = inpaint_volume(
        volume, np.asarray(mask) > 0, channel_axis=axis, method=method, spacing=info.spacing,
        device=args.device, progress=show_progress(),
    )  # fmt: skip
    return _done(args.output, out, info, f"inpaint (volume, {method})")
