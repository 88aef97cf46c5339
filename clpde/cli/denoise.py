"""`clpde denoise`: total-variation (ROF) denoising (clpde.rof)."""

from __future__ import annotations

import sys

import numpy as np

from ..imagedata import InputError
from ._common import add_image_arguments, load_input, save_output, show_progress, split_alpha


def add_denoise_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "denoise", help="total-variation (ROF) denoising",
        description="Rudin-Osher-Fatemi denoising run to a steady state. Give the noise level "
                    "--sigma (image units: 0..255 for 8-bit) or the strength --weight; with "
                    "neither, sigma is estimated from the image.",
    )
    add_image_arguments(parser)
    strength = parser.add_mutually_exclusive_group()
    strength.add_argument("--sigma", type=float, default=None,
                          help="noise standard deviation in the image's units")
    strength.add_argument("--weight", type=float, default=None,
                          help="denoising strength as in scikit-image (1/lambda on [0, 1] data)")
    parser.add_argument("--method", choices=("primal-dual", "gradient"), default="primal-dual",
                        help="primal-dual (exact TV, default) or gradient (the thesis's "
                             "explicit scheme)")
    parser.add_argument("--per-channel", action="store_true",
                        help="colour: TV of each channel on its own (default: colour-coupled "
                             "TV, whose channels keep their edges in the same places)")
    parser.add_argument("--eps", type=float, default=None,
                        help="--method gradient: regularisation of |grad u| (default 0.02)")
    parser.add_argument("--max-steps", type=int, default=None,
                        help="iteration cap (default: 500 primal-dual, 2000 gradient)")
    parser.set_defaults(run=run_denoise)


def run_denoise(args) -> int:
    from ..rof import denoise_tv

    if args.eps is not None and args.method != "gradient":
        raise InputError("--eps applies to --method gradient only")
    image = load_input(args)
    parts = split_alpha(image, args.input)
    options = {"method": args.method}
    if args.per_channel:
        options["vectorial"] = False
    if args.eps is not None:
        options["eps"] = args.eps
    if args.max_steps is not None:
        options["max_steps"] = args.max_steps
    result, info = denoise_tv(parts.colour, sigma=args.sigma, weight=args.weight,
                              channel_axis=parts.channel_axis, device=args.device,
                              progress=show_progress(), return_info=True, **options)
    save_output(args, parts.join(result))
    state = "converged" if info.converged else "stopped at --max-steps"
    residual = float(np.sqrt(np.mean(info.residual_variance)))
    noise = ""
    if info.sigma is not None:
        levels = ", ".join(f"{s:.4g}" for s in np.atleast_1d(info.sigma))
        noise = f", noise sigma {'estimated' if info.sigma_estimated else 'given'} {levels}"
    print(f"denoise: {info.steps} {args.method} iterations ({state}), residual std "
          f"{residual:.4g}{noise}", file=sys.stderr)
    return 0
