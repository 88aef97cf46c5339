"""`clpde surface`: a chapter-4 flow on the implicit surface of a mesh (clpde.surface); the
runs themselves are clpde.surface.runs'."""

from __future__ import annotations

from ..errors import InputError
from ..scale.file_tasks import TASKS
from ..surface.implicit import STORAGES
from ..surface.inpaint_files import inpaint_file
from ..surface.inpainting import METHODS as INPAINT_METHODS
from ..surface.runs import FLOWS
from ..surface.shapes import SURFACE_SHAPES as SHAPES
from ._common import (
    add_device_argument,
    add_output_folder_arguments,
    grid_advice,
    report,
    show_progress,
)


def add_surface_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "surface",
        help="run a PDE on a surface given by a mesh (thesis ch. 4)",
        description="Run a chapter-4 flow intrinsically on the implicit surface of MESH (any "
        "file trimesh reads, or one of the shapes " + ", ".join(SHAPES) + "), on "
        "a narrow band of a 3D grid. Writes OUTDIR/before.png, OUTDIR/after.png "
        "and the coloured result as OUTDIR/result.ply and OUTDIR/result.glb. "
        "Flows: heat (fig. 4.3), tv and denoise (fig. 4.4), chroma (colour "
        "denoising by harmonic maps, fig. 4.6), reaction-diffusion (fig. 4.7), "
        "flowvis (fig. 4.8), curvature; inpaint fills the vertices a MASK file names "
        "(--missing) from the mesh's vertex colours or a --values file.",
    )
    choices = FLOWS + ("inpaint",)
    parser.add_argument("flow", metavar="FLOW", choices=choices, help=" | ".join(choices))
    parser.add_argument("mesh", metavar="MESH", help="mesh file or shape name")
    add_output_folder_arguments(parser)
    parser.add_argument(
        "--resolution",
        type=int,
        default=96,
        help="grid cells across the shape's longest side (default: 96)",
    )
    parser.add_argument(
        "--t",
        type=float,
        default=None,
        help="evolution time (default: chosen per flow from the grid spacing)",
    )
    parser.add_argument(
        "--iterations", type=int, default=None, help="reaction-diffusion iterations (default: 4000)"
    )
    parser.add_argument(
        "--sigma",
        type=float,
        default=0.15,
        help="noise level: added to the demonstration data of tv, denoise and "
        "chroma, or that of the mesh's own colours for denoise "
        "(default: 0.15)",
    )
    parser.add_argument(
        "--data",
        choices=("auto", "mesh", "pattern"),
        default="auto",
        help="what heat, tv, denoise and chroma process: the mesh file's vertex "
        "colours ('mesh'), or a checkerboard / colour pattern with added "
        "noise ('pattern'); 'auto' (default) takes the colours when the "
        "mesh has them",
    )
    parser.add_argument(
        "--direction",
        choices=("major", "minor", "none"),
        default="major",
        help="principal direction for flowvis and anisotropic "
        "reaction-diffusion ('none': isotropic; default: major)",
    )
    parser.add_argument(
        "--size", type=int, default=400, help="picture size per view (default: 400)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    parser.add_argument(
        "--on",
        choices=("input", "remesh"),
        default=None,
        help="the mesh the results are written on: 'input', the mesh file "
        "given, with the values sampled at its own vertices (the default "
        "for a mesh file), or 'remesh', a marching-cubes mesh of the "
        "surface (the default, and the only choice, for a named shape)",
    )
    parser.add_argument(
        "--storage",
        choices=STORAGES,
        default="lists",
        help="the band's storage on the device: lists over the dense grid "
        "(default), or only the band's bricks (less memory; as fast from "
        "about 200 cells across)",
    )
    parser.add_argument(
        "--missing",
        metavar="MASK",
        help="inpaint: the vertices to fill, a .npy file of booleans (one per vertex) or "
        "of vertex indices, or a text file of vertex indices",
    )
    parser.add_argument(
        "--values",
        metavar="FILE",
        help="inpaint: the data to fill, one row per vertex (a scalar or RGB), as .npy or "
        "text; default: the mesh's vertex colours",
    )
    parser.add_argument(
        "--method",
        choices=INPAINT_METHODS,
        default="harmonic",
        help="inpaint: the PDE that fills the hole (default: harmonic)",
    )
    add_device_argument(parser)
    parser.set_defaults(run=run_surface)


def task_options(args) -> dict:
    """The surface task's keywords from the parsed flags (clpde.scale.file_tasks.surface_file)."""
    return {
        "flow": args.flow,
        "resolution": args.resolution,
        "t": args.t,
        "iterations": args.iterations,
        "sigma": args.sigma,
        "data": args.data,
        "direction": args.direction,
        "size": args.size,
        "seed": args.seed,
        "storage": args.storage,
        "on": args.on,
        "overwrite": args.overwrite,
        "device": args.device,
    }


def run_surface(args) -> int:
    if args.flow == "inpaint" or args.missing is not None:
        return run_surface_inpaint(args)
    with grid_advice(args.resolution):
        lines = TASKS["surface"](
            args.mesh, args.output, progress=show_progress(), **task_options(args)
        )
    report(lines)
    return 0


def run_surface_inpaint(args) -> int:
    if args.flow != "inpaint":
        raise InputError(f"--missing is for the inpaint flow, not {args.flow}")
    if args.missing is None:
        raise InputError("surface inpaint needs --missing MASK: the vertices to fill")
    with grid_advice(args.resolution):
        lines = inpaint_file(
            args.mesh,
            args.output,
            missing=args.missing,
            values=args.values,
            method=args.method,
            resolution=args.resolution,
            size=args.size,
            overwrite=args.overwrite,
            device=args.device,
            progress=show_progress(),
        )
    report(lines)
    return 0
