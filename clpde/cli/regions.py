"""`clpde regions`: region tracking on a deforming surface (clpde.regions)."""

from __future__ import annotations

import os
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


def add_regions_parser(subparsers) -> None:
    from ..regions_demo import FLOWS, SCENES

    parser = subparsers.add_parser(
        "regions", help="track painted regions on a deforming surface (thesis 2.2)",
        description="Track regions on a surface that deforms by level sets (thesis section "
                    "2.2). SCENE is one of " + ", ".join(SCENES) + " (Figure 2.7's toy cases "
                    "and caps on a sphere), or a mesh file: its surface evolves by --flow, with "
                    "regions from its vertex colours or the sign of its Gaussian curvature. "
                    "Writes OUTDIR/regions_K.ply per saved time (per-vertex region colours) "
                    "and OUTDIR/regions.png (saved times top to bottom).",
    )
    parser.add_argument("scene", metavar="SCENE", help="scene name or mesh file")
    add_output_folder_arguments(parser)
    parser.add_argument("--flow", choices=FLOWS, default="gaussian",
                        help="surface motion for a mesh file (default: gaussian, the positive "
                             "part of the Gaussian curvature, which flattens folds but barely "
                             "moves a smooth convex mesh: the output says when the surface "
                             "hardly moved)")
    parser.add_argument("--regions", choices=("auto", "colours", "curvature"), default="auto",
                        help="regions on a mesh file: one per flat vertex colour ('colours'), "
                             "or where its Gaussian curvature is positive ('curvature'); "
                             "'auto' (default) takes the colours when the mesh has them")
    parser.add_argument("--spacing", type=float, default=0.05,
                        help="grid spacing of the named scenes (default: 0.05)")
    parser.add_argument("--resolution", type=int, default=96,
                        help="grid cells across a mesh's longest side (default: 96)")
    parser.add_argument("--t", type=float, default=None, help="final time (default: per scene)")
    parser.add_argument("--saves", type=int, default=4, help="saved intervals (default: 4)")
    parser.add_argument("--size", type=int, default=256, help="picture size per view (default: 256)")
    add_device_argument(parser)
    parser.set_defaults(run=run_regions)


def run_regions(args) -> int:
    from ..regions_demo import SCENES, displacement, mesh_scene, run_scene, toy_scene, write_frames

    get_runtime(args.device)
    check_output_folder_args(args, [] if args.scene in SCENES else [args.scene])
    if args.size < 16:
        raise InputError(f"--size must be at least 16, not {args.size}")
    if args.scene not in SCENES and not os.path.exists(args.scene):
        raise InputError(f"{args.scene!r} is neither a mesh file nor one of the scenes "
                         f"{', '.join(SCENES)}")
    if args.scene in SCENES:
        scene = toy_scene(args.scene, args.spacing)
        if args.t is not None:
            scene.options["t"] = args.t
    else:
        if show_progress():  # the grid and the regions take a while before the steps begin
            print(f"regions: building a grid of {args.resolution} cells across {args.scene} "
                  "and its regions...", file=sys.stderr, flush=True)
        with grid_advice(args.resolution):
            scene = mesh_scene(args.scene, args.flow, args.resolution, args.t, args.regions)
    frames = run_scene(scene, saves=args.saves, progress=show_progress(), device=args.device)
    written = write_frames(frames, args.output, size=args.size,
                           views=((30.0, 25.0), (-60.0, 35.0)), overwrite=args.overwrite)
    share = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
    print(f"regions {args.scene}: grid {'x'.join(map(str, scene.phi.shape[::-1]))}, region 0 "
          f"area fraction {share} at t = {', '.join(f'{f.time:g}' for f in frames)}; wrote "
          f"{len(written)} files to {args.output}", file=sys.stderr)
    moved = displacement(scene, frames[-1]) / scene.spacing
    if args.scene not in SCENES and moved < 1.0:
        print(f"regions: the surface hardly moved (at most {moved:.2f} grid cells; area "
              f"{frames[0].area():.4g} -> {frames[-1].area():.4g}): {FLOW_MOTION[args.flow]}",
              file=sys.stderr)
    return 0


FLOW_MOTION = {
    "gaussian": "--flow gaussian moves only where the surface is strongly curved (folds, "
                "creases), and a smooth convex mesh has no such parts; --flow morph-sphere "
                "moves any shape but a sphere, or give a larger --t",
    "mean-curvature": "give a larger --t (the surface moves about 2t/R for radius R), or "
                      "--flow morph-sphere",
    "morph-sphere": "the mesh is nearly a sphere already; --flow mean-curvature with a larger "
                    "--t shrinks it",
}
