"""`clpde denoise`: total-variation (ROF) denoising (clpde.planar.rof)."""

from __future__ import annotations

from ..io.volumes import is_volume_file
from ..scale.file_tasks import TASKS
from ._common import add_image_arguments, output_path, report, show_progress
from .volumes import run_volume_denoise


def add_denoise_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "denoise",
        help="total-variation (ROF) denoising",
        description="Rudin-Osher-Fatemi denoising run to a steady state. Give the noise level "
        "--sigma (image units: 0..255 for 8-bit) or the strength --weight; with "
        "neither, sigma is estimated from the image. A volume (.nii, .nii.gz, or a TIFF of several "
        "pages) is denoised in 3D with its voxel spacing, into a volume file.",
    )
    add_image_arguments(parser)
    strength = parser.add_mutually_exclusive_group()
    strength.add_argument(
        "--sigma", type=float, default=None, help="noise standard deviation in the image's units"
    )
    strength.add_argument(
        "--weight",
        type=float,
        default=None,
        help="denoising strength as in scikit-image (1/lambda on [0, 1] data)",
    )
    parser.add_argument(
        "--method",
        choices=("primal-dual", "gradient"),
        default="primal-dual",
        help="primal-dual (exact TV, default) or gradient (the thesis's explicit scheme)",
    )
    parser.add_argument(
        "--per-channel",
        action="store_true",
        help="colour: TV of each channel on its own (default: colour-coupled "
        "TV, whose channels keep their edges in the same places)",
    )
    parser.add_argument(
        "--eps",
        type=float,
        default=None,
        help="--method gradient: regularisation of |grad u| (default 0.02)",
    )
    parser.add_argument(
        "--max-steps",
        type=int,
        default=None,
        help="iteration cap (default: 500 primal-dual, 2000 gradient; images of over 2^22 "
        "values run in tiles of at most 50 each)",
    )
    parser.set_defaults(run=run_denoise)


def task_options(args) -> dict:
    """The denoise task's keywords from the parsed flags (clpde.scale.file_tasks.denoise_file)."""
    return {
        "sigma": args.sigma,
        "weight": args.weight,
        "method": args.method,
        "eps": args.eps,
        "max_steps": args.max_steps,
        "per_channel": args.per_channel,
        "device": args.device,
    }


def run_denoise(args) -> int:
    args.output = output_path(args)
    if is_volume_file(args.input):  # NIfTI or a TIFF of several pages: clpde.volumes
        return run_volume_denoise(args)
    report(
        TASKS["denoise"](args.input, args.output, progress=show_progress(), **task_options(args))
    )
    return 0
