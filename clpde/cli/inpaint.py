"""`clpde inpaint`: fill a masked region of an image (clpde.inpaint)."""

from __future__ import annotations

import sys

import numpy as np

from ..imagedata import InputError
from ..io import check_not_overwriting_input, read_image
from ..runtime import get_runtime
from ..video import add_sequence_arguments, prepare_sequence_args, run_sequence_inpaint
from ._common import add_device_argument, load_input, save_output, show_progress, split_alpha


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
                        help="mask image of the same size; nonzero (white) = inpaint")
    parser.add_argument("-o", "--output", metavar="OUT", required=True,
                        help="output image (with --demo: an output folder)")
    parser.add_argument("--demo", action="store_true",
                        help="inpaint a bundled damaged photo; writes PNGs into the folder OUT")
    parser.add_argument("--gif", metavar="EVOLUTION.gif", default=None,
                        help="also write the evolution as an animated GIF")
    parser.add_argument("--gif-every", type=int, default=100, metavar="N",
                        help="steps between GIF frames (default: 100)")
    parser.add_argument("--max-steps", type=int, default=3000, help="per level (default: 3000)")
    parser.add_argument("--tol", type=float, default=1e-4,
                        help="stop when the largest change in the region over a check interval "
                             "is below this, intensities in [0, 1] (default: 1e-4; 0 = off)")
    parser.add_argument("--mean-tol", type=float, default=4e-4,
                        help="stop when the mean change in the region over a check interval "
                             "is below this (default: 4e-4; 0 = off)")
    parser.add_argument("--dt", type=float, default=0.1, help="time step (default: 0.1)")
    parser.add_argument("--scaling", choices=("none", "quartic-root"), default="none",
                        help="transport update as in eq. 3.6 (none) or appendix A's "
                             "sign(c)|c|^(1/4) (default: none)")
    parser.add_argument("--colour", choices=("channels", "rho-phi-psi"), default="channels",
                        help="colour model (default: channels)")
    parser.add_argument("--levels", type=int, default=None,
                        help="multiresolution levels (default: chosen from the mask)")
    add_device_argument(parser)
    add_sequence_arguments(parser)  # a video or an image folder: clpde/video.py
    parser.set_defaults(run=run_inpaint)


def _read_inpaint_mask(path, shape) -> np.ndarray:
    mask = read_image(path)
    if mask.ndim == 3:  # colour mask: any colour channel; an alpha channel is ignored
        channels = mask.shape[-1] - 1 if mask.shape[-1] in (2, 4) else mask.shape[-1]
        mask = (mask[..., :channels] != 0).any(axis=-1)
    if mask.shape != tuple(shape):
        raise InputError(f"mask {path} is {mask.shape[1]}x{mask.shape[0]} pixels but the image "
                         f"is {shape[1]}x{shape[0]}; give a mask of the same size")
    return mask != 0


def run_inpaint(args) -> int:
    from ..inpaint import inpaint
    from ..io import write_gif

    if prepare_sequence_args(args):  # a film or a folder of frames, over Dask workers
        return run_sequence_inpaint(args)
    if args.gif_every < 1:
        raise InputError(f"--gif-every must be at least 1, not {args.gif_every}")
    if args.demo:
        from ..inpaint_demo import run_demo

        if args.input or args.mask or args.gif:
            raise InputError(
                "--demo takes no IMAGE, MASK or --gif; it writes into the folder -o OUT")
        get_runtime(args.device)
        written = run_demo(args.output, device=args.device, progress=show_progress())
        print(f"wrote {len(written)} files to {args.output}", file=sys.stderr)
        return 0
    if not args.input or not args.mask:
        raise InputError("give IMAGE and MASK (or --demo)")
    if args.gif:
        check_not_overwriting_input([args.input, args.mask], args.gif)
        if not str(args.gif).lower().endswith(".gif"):
            raise InputError(f"--gif {args.gif}: the animation must be a .gif file")
    image = load_input(args, args.mask)
    mask = _read_inpaint_mask(args.mask, image.shape[:2])
    parts = split_alpha(image, args.input)
    options = {"channel_axis": parts.channel_axis, "dt": args.dt, "scaling": args.scaling,
               "colour": args.colour, "levels": args.levels, "max_steps": args.max_steps,
               "tol": args.tol, "mean_tol": args.mean_tol, "device": args.device,
               "progress": show_progress(), "return_info": True}
    if args.gif:
        result, info = inpaint(parts.colour, mask, snapshots=args.gif_every, **options)
    else:
        result, info = inpaint(parts.colour, mask, **options)
    save_output(args, parts.join(result))
    if args.gif:
        write_gif(args.gif, [s.image for s in info.snapshots])
        print(f"wrote {args.gif} ({len(info.snapshots)} frames)", file=sys.stderr)
    state = "converged" if info.converged else "stopped at --max-steps"
    print(f"inpaint: {int(mask.sum())} pixels, {info.steps} steps ({state}), "
          f"{info.levels} level(s), {info.seconds:.2f} s", file=sys.stderr)
    return 0
