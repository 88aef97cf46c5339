"""`clpde diffuse`: a planar diffusion flow on an image (clpde.planar)."""

from __future__ import annotations

from ..io.volumes import is_volume_file
from ..planar.flows import FLOW_PARAMS, FLOWS
from ..scale.file_tasks import TASKS
from ._common import add_image_arguments, output_path, param_check, report, show_progress
from .volumes import run_volume_diffuse


def add_diffuse_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "diffuse",
        help="run a planar diffusion flow on an image",
        description="Run heat, Perona-Malik, TV or curvature diffusion for a number of "
        "explicit steps. Colour images are processed per channel. A volume (.nii, .nii.gz, or a "
        "TIFF of several pages) runs the 3D flow (heat, perona-malik or tv) with its spacing.",
    )
    add_image_arguments(parser)
    parser.add_argument("--flow", choices=FLOWS, default="heat", help="default: heat")
    parser.add_argument("--steps", type=int, default=100, help="explicit steps (default: 100)")
    parser.add_argument(
        "--dt", type=float, default=None, help="time step (default: 0.8 of the stability limit)"
    )
    parser.add_argument(
        "--kappa",
        type=float,
        default=None,
        help="Perona-Malik edge threshold, intensities in [0, 1] (default 0.05)",
    )
    parser.add_argument(
        "--edge",
        choices=("exp", "rational"),
        default=None,
        help="Perona-Malik edge-stopping function (default: exp)",
    )
    parser.add_argument(
        "--presmooth",
        type=float,
        default=None,
        help="Perona-Malik: read the edge-stopping function from the image "
        "smoothed by a Gaussian of this many pixels (the regularised "
        "flow of Catte et al.; isolated noise spikes then diffuse too)",
    )
    parser.add_argument(
        "--eps",
        type=float,
        default=None,
        help="TV / curvature regularisation of |grad u|, intensities in [0, 1] "
        "(TV default 0.005, about one 8-bit grey level: regions flatten, "
        "edges stay)",
    )
    parser.set_defaults(run=run_diffuse)


def task_options(args) -> dict:
    """The diffuse task's keywords from the parsed flags (clpde.scale.file_tasks.diffuse_file)."""
    return {
        "flow": args.flow,
        "steps": args.steps,
        "dt": args.dt,
        "kappa": args.kappa,
        "edge": args.edge,
        "eps": args.eps,
        "presmooth": args.presmooth,
        "device": args.device,
    }


def run_diffuse(args) -> int:
    args.output = output_path(args)
    param_check(
        args,
        args.flow,
        {
            option: tuple(f for f, params in FLOW_PARAMS.items() if option in params)
            for option in ("kappa", "edge", "eps", "presmooth")
        },
    )
    if is_volume_file(args.input):  # NIfTI or a TIFF of several pages: clpde.volumes
        names = ("kappa", "edge", "eps", "presmooth")
        params = {k: getattr(args, k) for k in names if getattr(args, k) is not None}
        return run_volume_diffuse(args, args.flow, params)
    report(
        TASKS["diffuse"](args.input, args.output, progress=show_progress(), **task_options(args))
    )
    return 0
