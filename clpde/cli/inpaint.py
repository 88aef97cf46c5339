"""`clpde inpaint`: fill a masked region of an image (clpde.inpaint)."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import InputError
from ..inpainting.registry import METHODS
from ..io.images import MASK_RULE
from ..io.volumes import is_volume_file
from ..runtime import get_runtime
from ..scale.file_tasks import TASKS, TRANSPORT_OPTIONS
from ._common import (
    add_device_argument,
    report,
    show_progress,
)
from ._inpaint_demo import check_demo_output, run_demo
from .restore import add_sequence_arguments, prepare_sequence_args, run_sequence_inpaint
from .volumes import run_volume_inpaint


def add_inpaint_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "inpaint",
        help="fill a masked region of an image (structure and texture)",
        description="Fill the pixels where MASK is white. The default method is pick "
        "(frequency-selective): each block of the hole a sparse sum of Fourier basis "
        "functions fitted to the known pixels around it (--method spectral), except where "
        "the hole sits in a periodic pattern, which the exemplar copies. --method coherence is "
        "coherence transport, isophotes continued into the hole, fastest. --method auto is "
        "the self-validated choice: per cluster of damage, the candidate methods "
        "fill a hidden ring of known pixels too, and the blend that fits it best "
        "fills the hole (better, and several times slower; docs/inpainting.md). "
        "--method transport is the thesis's scheme (chapter 3): smoothness "
        "transported along the isophotes, interleaved with anisotropic diffusion, "
        "to a steady state; its options are marked 'transport:' below. Colour "
        "images are inpainted per channel (or in the rho, sin phi, sin psi "
        "model); an alpha channel is kept as is. "
        "--demo damages a bundled photo and restores it. A volume (.nii, .nii.gz, or a TIFF "
        "of several pages) with a volume MASK is filled by the 3D biharmonic fill (or --method "
        "spectral) with its voxel spacing, into a volume file.",
    )
    _add_input_output_arguments(parser)
    _add_transport_arguments(parser)
    _add_method_arguments(parser)
    add_device_argument(parser)
    add_sequence_arguments(parser)  # a film or a frame folder: clpde restore's path
    parser.set_defaults(run=run_inpaint)


def _add_input_output_arguments(parser) -> None:
    """IMAGE, MASK, the output, the demo and the evolution's GIF."""
    parser.add_argument("input", metavar="IMAGE", nargs="?", help="image to restore")
    parser.add_argument(
        "mask",
        metavar="MASK",
        nargs="?",
        help="mask image of the same size; white = inpaint (" + MASK_RULE + "); "
        "or the word 'nan' to fill the NaN pixels of a float TIFF",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUT",
        required=True,
        help="output image (with --demo: the folder in which the demo's folder "
        "inpaint_demo is written)",
    )
    parser.add_argument(
        "--demo",
        action="store_true",
        help="inpaint a bundled damaged photo; writes PNGs into OUT/inpaint_demo, as "
        "examples/inpaint_demo.py does (OUT is created if missing; a rerun replaces the "
        "demo's own files)",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="with --demo: replace OUT/inpaint_demo even if it holds other files "
        "(only clpde's kinds of output files)",
    )
    parser.add_argument(
        "--gif",
        metavar="EVOLUTION.gif",
        default=None,
        help="also write the evolution as an animated GIF",
    )
    parser.add_argument(
        "--gif-every",
        type=int,
        default=100,
        metavar="N",
        help="steps between GIF frames (default: 100)",
    )


def _add_transport_arguments(parser) -> None:
    """The thesis's scheme's options (a call giving one runs method="transport"), and the
    colour model and levels that it shares with other methods."""
    parser.add_argument(
        "--max-steps", type=int, default=None, help="transport: steps per level (default: 3000)"
    )
    parser.add_argument(
        "--tol",
        type=float,
        default=None,
        help="transport: stop when the largest change in the region over a check interval "
        "is below this, intensities in [0, 1] (default: 1e-4; 0 = off)",
    )
    parser.add_argument(
        "--mean-tol",
        type=float,
        default=None,
        help="transport: stop when the mean change in the region over a check interval "
        "is below this (default: 4e-4; 0 = off)",
    )
    parser.add_argument(
        "--dt", type=float, default=None, help="transport: time step (default: 0.1)"
    )
    parser.add_argument(
        "--scaling",
        choices=("none", "quartic-root"),
        default=None,
        help="transport: the update as in eq. 3.6 (none) or appendix A's "
        "sign(c)|c|^(1/4) (default: none)",
    )
    parser.add_argument(
        "--colour",
        choices=("channels", "rho-phi-psi"),
        default="channels",
        help="colour model (default: channels)",
    )
    parser.add_argument(
        "--levels",
        type=int,
        default=None,
        help="transport: multiresolution levels (default: chosen from the mask)",
    )


def _add_method_arguments(parser) -> None:
    """The method's choice and the options every method takes."""
    parser.add_argument(
        "--method",
        choices=("auto", *METHODS),
        default=None,
        help="inpainting method (default: pick, the spectral fill with periodic patterns "
        "copied; 'transport', the thesis's scheme, when one of its options above or --gif "
        "is given; 'auto': the self-validated choice, docs/inpainting.md)",
    )
    parser.add_argument(
        "--grow",
        type=float,
        default=0,
        metavar="PX",
        help="grow the mask by a disc of PX pixels first, to take in a "
        "damage's blurred rim (default: 0)",
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=None,
        metavar="N",
        help="the random search's seed of the exemplar method (the same seed "
        "gives the same result; default: 0)",
    )
    parser.add_argument(
        "--soft-mask",
        action="store_true",
        help="read MASK's grey levels as the degree of damage (black 0 = "
        "keep, white = inpaint, grey = partly damaged: keeps a fidelity "
        "to the observed pixel) instead of bright = inpaint",
    )


def task_options(args) -> dict:
    """The inpaint task's keywords from the parsed flags (clpde.scale.file_tasks.inpaint_file)."""
    return {
        "method": args.method,
        "colour": args.colour,
        "levels": args.levels,
        "soft_mask": args.soft_mask,
        "gif": args.gif,
        "gif_every": args.gif_every,
        "grow": args.grow,
        "seed": args.seed,
        **{name: getattr(args, name) for name in TRANSPORT_OPTIONS},
        "device": args.device,
    }


def run_inpaint(args) -> int:
    if prepare_sequence_args(args):  # a film or a folder of frames: clpde restore's path
        return run_sequence_inpaint(args)
    if args.gif_every < 1:
        raise InputError(f"--gif-every must be at least 1, not {args.gif_every}")
    if not np.isfinite(args.grow) or args.grow < 0:
        raise InputError(f"--grow must be a number of pixels >= 0, not {args.grow:g}")
    if args.demo:
        if args.input or args.mask or args.gif:
            raise InputError(
                "--demo takes no IMAGE, MASK or --gif; it writes into the folder -o OUT"
            )
        get_runtime(args.device)
        folder = check_demo_output(args.output, args.overwrite)
        written = run_demo(
            args.output, device=args.device, progress=show_progress(), overwrite=args.overwrite
        )
        print(f"wrote {len(written)} files to {folder}", file=sys.stderr)
        return 0
    if not args.input or not args.mask:
        raise InputError("give IMAGE and MASK (or --demo)")
    if is_volume_file(args.input):  # NIfTI or a TIFF of several pages: clpde.volumes
        return run_volume_inpaint(args)
    if args.overwrite:
        raise InputError(
            "--overwrite is for --demo's output folder; an output image is always replaced"
        )
    report(
        TASKS["inpaint"](
            args.input, args.output, mask=args.mask, progress=show_progress(), **task_options(args)
        )
    )
    return 0
