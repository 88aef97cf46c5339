"""`clpde surface`: a chapter-4 flow on the implicit surface of a mesh (clpde.surface)."""

from __future__ import annotations

import sys

from ..imagedata import InputError
from ..runtime import get_runtime
from ._common import (
    add_device_argument,
    add_output_folder_arguments,
    check_output_folder_args,
    grid_advice,
    show_progress,
)


def add_surface_parser(subparsers) -> None:
    from ..surface.demo import FLOWS, SHAPES

    parser = subparsers.add_parser(
        "surface", help="run a PDE on a surface given by a mesh (thesis ch. 4)",
        description="Run a chapter-4 flow intrinsically on the implicit surface of MESH (any "
                    "file trimesh reads, or one of the shapes " + ", ".join(SHAPES) + "), on "
                    "a narrow band of a 3D grid. Writes OUTDIR/before.png, OUTDIR/after.png "
                    "and the coloured result as OUTDIR/result.ply and OUTDIR/result.glb. "
                    "Flows: heat (fig. 4.3), tv and denoise (fig. 4.4), chroma (colour "
                    "denoising by harmonic maps, fig. 4.6), reaction-diffusion (fig. 4.7), "
                    "flowvis (fig. 4.8), curvature.",
    )
    parser.add_argument("flow", metavar="FLOW", choices=FLOWS, help=" | ".join(FLOWS))
    parser.add_argument("mesh", metavar="MESH", help="mesh file or shape name")
    add_output_folder_arguments(parser)
    parser.add_argument("--resolution", type=int, default=96,
                        help="grid cells across the shape's longest side (default: 96)")
    parser.add_argument("--t", type=float, default=None,
                        help="evolution time (default: chosen per flow from the grid spacing)")
    parser.add_argument("--iterations", type=int, default=None,
                        help="reaction-diffusion iterations (default: 4000)")
    parser.add_argument("--sigma", type=float, default=0.15,
                        help="noise level: added to the demonstration data of tv, denoise and "
                             "chroma, or that of the mesh's own colours for denoise "
                             "(default: 0.15)")
    parser.add_argument("--data", choices=("auto", "mesh", "pattern"), default="auto",
                        help="what heat, tv, denoise and chroma process: the mesh file's vertex "
                             "colours ('mesh'), or a checkerboard / colour pattern with added "
                             "noise ('pattern'); 'auto' (default) takes the colours when the "
                             "mesh has them")
    parser.add_argument("--direction", choices=("major", "minor", "none"), default="major",
                        help="principal direction for flowvis and anisotropic "
                             "reaction-diffusion ('none': isotropic; default: major)")
    parser.add_argument("--size", type=int, default=400, help="picture size per view (default: 400)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    add_device_argument(parser)
    parser.set_defaults(run=run_surface)


def run_surface(args) -> int:
    from ..surface.demo import DATA_FLOWS, load_surface, mesh_colours, run_flow, write_run

    get_runtime(args.device)
    check_output_folder_args(args, [args.mesh])
    if args.resolution < 16:
        raise InputError(f"--resolution must be at least 16, not {args.resolution}")
    if args.size < 16:
        raise InputError(f"--size must be at least 16, not {args.size}")
    if args.direction == "none" and args.flow == "flowvis":
        raise InputError("flowvis needs --direction major or minor")
    with grid_advice(args.resolution):
        surf = load_surface(args.mesh, args.resolution, device=args.device)
    data = None
    if args.data != "pattern" and args.flow in DATA_FLOWS:
        data = mesh_colours(surf)
        if data is None and args.data == "mesh":
            raise InputError(f"{args.mesh} has no vertex colours; use --data pattern")
    run = run_flow(surf, args.flow, t=args.t, iterations=args.iterations, sigma=args.sigma,
                   seed=args.seed, direction=args.direction, data=data, progress=show_progress())
    written = write_run(run, args.output, size=args.size, overwrite=args.overwrite)
    print(f"surface {args.flow}: {run.note}; grid {'x'.join(map(str, surf.shape[::-1]))}, band "
          f"{surf.ext_band.n} cells; wrote {len(written)} files to {args.output}", file=sys.stderr)
    return 0
