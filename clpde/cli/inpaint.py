"""`clpde inpaint`: fill a masked region of an image (clpde.inpaint)."""

from __future__ import annotations

import os
import sys

import numpy as np

from ..imagedata import InputError
from ..io import MASK_RULE, check_not_overwriting_input, read_image, read_mask
from ..runtime import get_runtime
from ._common import (
    OUTPUT_FOLDER_RULE,
    add_device_argument,
    check_output_folder_args,
    load_input,
    save_output,
    show_progress,
    split_alpha,
)
from .restore import add_sequence_arguments, prepare_sequence_args, run_sequence_inpaint


def add_inpaint_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "inpaint", help="fill a masked region by continuing the isophotes (thesis ch. 3)",
        description="Inpaint the pixels where MASK is nonzero (thesis chapter 3): smoothness "
                    "is transported along the isophotes arriving at the region, interleaved "
                    "with anisotropic diffusion, until a steady state. Colour images are "
                    "inpainted per channel (or in the rho, sin phi, sin psi model); an alpha "
                    "channel is kept as is. --demo damages a bundled photo and restores it.",
    )
    parser.add_argument("input", metavar="IMAGE", nargs="?", help="image to restore")
    parser.add_argument("mask", metavar="MASK", nargs="?",
                        help="mask image of the same size; white = inpaint (" + MASK_RULE + "); "
                             "or the word 'nan' to fill the NaN pixels of a float TIFF")
    parser.add_argument("-o", "--output", metavar="OUT", required=True,
                        help="output image (with --demo: an output folder)")
    parser.add_argument("--demo", action="store_true",
                        help="inpaint a bundled damaged photo; writes PNGs into the folder OUT "
                             "(" + OUTPUT_FOLDER_RULE + ")")
    parser.add_argument("--overwrite", action="store_true",
                        help="with --demo: replace the folder OUT's contents (only a folder of "
                             "clpde's kinds of output files)")
    parser.add_argument("--gif", metavar="EVOLUTION.gif", default=None,
                        help="also write the evolution as an animated GIF")
    parser.add_argument("--gif-every", type=int, default=100, metavar="N",
                        help="steps between GIF frames (default: 100)")
    parser.add_argument("--max-steps", type=int, default=None,
                        help="transport: steps per level (default: 3000)")
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
    parser.add_argument("--dt", type=float, default=None,
                        help="transport: time step (default: 0.1)")
    parser.add_argument("--scaling", choices=("none", "quartic-root"), default=None,
                        help="transport: the update as in eq. 3.6 (none) or appendix A's "
                             "sign(c)|c|^(1/4) (default: none)")
    parser.add_argument("--colour", choices=("channels", "rho-phi-psi"), default="channels",
                        help="colour model (default: channels)")
    parser.add_argument("--levels", type=int, default=None,
                        help="multiresolution levels (default: chosen from the mask)")
    from ..inpainting import METHODS

    parser.add_argument("--method", choices=("auto", *METHODS), default=None,
                        help="inpainting method (default: auto, coherence transport where "
                             "installed, the best on the benchmark, docs/inpainting.md; "
                             "'transport', the thesis's scheme, when one of its options "
                             "above or --gif is given)")
    parser.add_argument("--soft-mask", action="store_true",
                        help="read MASK's grey levels as the degree of damage (black 0 = "
                             "keep, white = inpaint, grey = partly damaged: keeps a fidelity "
                             "to the observed pixel) instead of bright = inpaint")
    add_device_argument(parser)
    add_sequence_arguments(parser)  # a film or a frame folder: clpde restore's path
    parser.set_defaults(run=run_inpaint)


def _read_soft_mask(path, shape) -> np.ndarray:
    """The mask's grey level over its dtype's range as a float degree of damage in [0, 1]
    (a colour mask: its brightest colour channel; an alpha channel is ignored)."""
    mask = read_image(path)
    if mask.ndim == 3:
        channels = mask.shape[-1] - 1 if mask.shape[-1] in (2, 4) else mask.shape[-1]
        mask = mask[..., :channels].max(axis=-1)
    if mask.shape != tuple(shape):
        raise InputError(f"mask {path} is {mask.shape[1]}x{mask.shape[0]} pixels but the image "
                         f"is {shape[1]}x{shape[0]}; give a mask of the same size")
    if np.issubdtype(mask.dtype, np.integer):
        return mask.astype(np.float32) / np.iinfo(mask.dtype).max
    return np.clip(mask.astype(np.float32), 0, 1)


TRANSPORT_OPTIONS = ("dt", "scaling", "max_steps", "tol", "mean_tol")


def run_inpaint(args) -> int:
    from ..inpaint import inpaint
    from ..io import write_gif

    if prepare_sequence_args(args):  # a film or a folder of frames: clpde restore's path
        return run_sequence_inpaint(args)
    if args.gif_every < 1:
        raise InputError(f"--gif-every must be at least 1, not {args.gif_every}")
    if args.demo:
        from ._inpaint_demo import run_demo

        if args.input or args.mask or args.gif:
            raise InputError(
                "--demo takes no IMAGE, MASK or --gif; it writes into the folder -o OUT")
        get_runtime(args.device)
        check_output_folder_args(args)
        written = run_demo(args.output, device=args.device, progress=show_progress(),
                           overwrite=args.overwrite)
        print(f"wrote {len(written)} files to {args.output}", file=sys.stderr)
        return 0
    if not args.input or not args.mask:
        raise InputError("give IMAGE and MASK (or --demo)")
    if args.overwrite:
        raise InputError("--overwrite is for --demo's output folder; an output image is "
                         "always replaced")
    if args.gif:
        check_not_overwriting_input([args.input, args.mask], args.gif)
        if not str(args.gif).lower().endswith(".gif"):
            raise InputError(f"--gif {args.gif}: the animation must be a .gif file")
        folder = os.path.dirname(os.path.abspath(args.gif))
        if not os.path.isdir(folder):
            raise InputError(f"the folder {folder} for --gif does not exist; create it first")
    nan_mask = args.mask.lower() == "nan" and not os.path.exists(args.mask)
    image = load_input(args, *([] if nan_mask else [args.mask]), allow_nan=True)
    finite = (np.isfinite(image) if np.issubdtype(image.dtype, np.floating)
              else np.ones(image.shape, bool))
    finite = finite.all(axis=-1) if finite.ndim == 3 else finite
    if nan_mask:
        if finite.all():
            raise InputError(f"{args.input} has no NaN pixels to fill (MASK 'nan'); give a mask "
                             "image of the pixels to inpaint")
        mask = ~finite
    else:
        if args.soft_mask:
            mask = _read_soft_mask(args.mask, image.shape[:2])
        else:
            mask = read_mask(args.mask, image.shape[:2])
        if not finite[~(mask > 0)].all():
            raise InputError(
                f"{args.input} has {int((~finite[~(mask > 0)]).sum())} NaN pixels outside the mask "
                f"{args.mask}; paint them into the mask, or give 'nan' as MASK to fill exactly "
                "the NaN pixels")
    parts = split_alpha(image, args.input)
    method = args.method
    if method is None and args.gif:
        method = "transport"  # the evolution the GIF shows is the thesis scheme's
    options = {"channel_axis": parts.channel_axis, "colour": args.colour,
               "levels": args.levels, "device": args.device, "progress": show_progress(),
               "return_info": True, "method": method}
    # only the transport options given, so that the default method can be chosen by them
    options.update({name: getattr(args, name) for name in TRANSPORT_OPTIONS
                    if getattr(args, name) is not None})
    if args.gif:
        result, info = inpaint(parts.colour, mask, snapshots=args.gif_every, **options)
    else:
        result, info = inpaint(parts.colour, mask, **options)
    save_output(args, parts.join(result))
    if args.gif:
        frames = evolution_frames(parts.colour, [s.image for s in info.snapshots])
        write_gif(args.gif, frames, duration=0.25)
        print(f"wrote {args.gif} ({len(frames)} frames: the damaged image, then every "
              f"{args.gif_every} steps from the start fill to the result)", file=sys.stderr)
    state = "converged" if info.converged else "stopped at --max-steps"
    steps = f"{info.steps} steps ({state}), {info.levels} level(s), " \
        if info.method == "transport" else ""
    print(f"inpaint: {int((mask > 0).sum())} pixels, method {info.method}, {steps}"
          f"{len(info.boxes)} box(es), {info.seconds:.2f} s", file=sys.stderr)
    return 0


def evolution_frames(damaged, states) -> list[np.ndarray]:
    """The GIF's frames as uint8: the damaged image first (its region shown as it came, NaN
    as black), then the states; all on one intensity scale (the result's range for floats),
    consecutive equal frames merged, since a GIF cannot show them apart."""
    frames = [np.asarray(damaged), *(np.asarray(s) for s in states)]
    result = frames[-1]
    if np.issubdtype(result.dtype, np.floating):
        finite = result[np.isfinite(result)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        scale = hi - lo if hi > lo else 1.0
        frames = [np.nan_to_num((f.astype(np.float64) - lo) / scale, nan=0.0, posinf=1.0,
                                neginf=0.0) for f in frames]
    from ..io import _frame_to_uint8

    out = []
    for frame in map(_frame_to_uint8, frames):
        if not out or not np.array_equal(frame, out[-1]):
            out.append(frame)
    return out
