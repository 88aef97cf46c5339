"""The `clpde` command line.

Each subcommand is one `add_<name>_parser(subparsers)` function registered with
`@subcommand`; it adds its arguments and sets `run=<function(args) -> exit status>`.
To add a capability, write those two functions in a new section below; the shared helpers
(`add_image_arguments`, `load_input`, `split_alpha`, `save_output`) do the file handling:
the input is never overwritten, the output is checked before any work and written
atomically, and colour images are processed per channel with any alpha channel kept as is.

Errors print one line `clpde: error: ...` on stderr and exit with status 2, writing nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from dataclasses import asdict, dataclass, replace

import numpy as np
import pyopencl as cl

from . import __version__
from .imagedata import InputError
from .io import check_not_overwriting_input, check_writable, image_format, read_image, write_image
from .runtime import ClpdeError, devices, get_runtime

SUBCOMMANDS = []
ERROR_STATUS = 2


def subcommand(add_parser):
    """Register an `add_<name>_parser(subparsers)` function as a subcommand."""
    SUBCOMMANDS.append(add_parser)
    return add_parser


# ---- shared helpers ----------------------------------------------------------------------

def add_device_argument(parser) -> None:
    parser.add_argument(
        "--device", metavar="SPEC", default=None,
        help="OpenCL device: 'cpu', 'gpu', an index or a name substring from `clpde devices` "
             "(default: $CLPDE_DEVICE, else a GPU if present, else the CPU)",
    )


def add_image_arguments(parser) -> None:
    """IN and OUT image paths and --device."""
    parser.add_argument("input", metavar="IN", help="input image (.png, .tif/.tiff, .jpg/.jpeg)")
    parser.add_argument("output", metavar="OUT",
                        help="output image; same formats; never the input file")
    add_device_argument(parser)


def show_progress() -> bool:
    """Progress bars go to stderr, so only draw them when stderr is a terminal."""
    return sys.stderr.isatty()


def load_input(args, *extra_inputs) -> np.ndarray:
    """Check the device and the output path, then read IN; all before any work is done."""
    get_runtime(args.device)  # an unknown device fails here, before reading anything
    check_not_overwriting_input([args.input, *extra_inputs], args.output)
    image_format(args.output)
    image = read_image(args.input)
    if image.dtype == bool:  # 1-bit files: compute on 0/255 and write 8-bit
        image = image.astype(np.uint8) * 255
    check_writable(args.output, image.dtype, image.shape)
    return image


@dataclass
class Channels:
    """An image split into the channels a flow works on and an untouched alpha channel."""

    colour: np.ndarray
    channel_axis: int | None
    alpha: np.ndarray | None
    squeezed: bool

    def join(self, result: np.ndarray) -> np.ndarray:
        """The flow's result on `colour` back in the input's layout, alpha restored."""
        result = np.asarray(result)
        if self.squeezed:
            result = result[..., np.newaxis]
        if self.alpha is not None:
            if result.ndim == 2:
                result = result[..., np.newaxis]
            result = np.concatenate([result, self.alpha[..., np.newaxis]], axis=-1)
        return result


def split_alpha(image: np.ndarray, name: str = "input") -> Channels:
    """Greyscale (rows, cols) or colour (rows, cols, 1..4); 2 and 4 channels end in alpha."""
    if image.ndim == 2:
        return Channels(image, None, None, False)
    if image.ndim != 3 or image.shape[-1] > 4:
        raise InputError(
            f"{name} has shape {image.shape}; expected a greyscale (rows, columns) or colour "
            "(rows, columns, channels<=4) image (multi-page TIFF stacks are not supported)"
        )
    alpha = None
    colour = image
    if image.shape[-1] in (2, 4):
        alpha, colour = image[..., -1], image[..., :-1]
    if colour.shape[-1] == 1:
        return Channels(colour[..., 0], None, alpha, alpha is None)
    return Channels(colour, -1, alpha, False)


def save_output(args, result: np.ndarray) -> None:
    write_image(args.output, result)
    print(f"wrote {args.output}", file=sys.stderr)


def _param_check(args, flow: str, allowed: dict) -> None:
    """Refuse options that the chosen flow would silently ignore."""
    for option, flows in allowed.items():
        if getattr(args, option) is not None and flow not in flows:
            raise InputError(f"--{option} applies to --flow {' or '.join(flows)}, not {flow}")


# ---- clpde devices -----------------------------------------------------------------------

@subcommand
def add_devices_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "devices", help="list OpenCL platforms and devices",
        description="List every OpenCL device; '*' marks the one clpde uses.",
    )
    parser.add_argument("--json", action="store_true", help="print a JSON list instead")
    add_device_argument(parser)
    parser.set_defaults(run=run_devices)


def run_devices(args) -> int:
    found = devices()
    if args.device is not None:
        chosen = get_runtime(args.device).index
        found = [replace(d, in_use=(d.index == chosen)) for d in found]
    if args.json:
        print(json.dumps([asdict(d) for d in found], indent=2))
        return 0
    for info in found:
        print(info.describe())
    print("(* = the device in use; choose with --device, CLPDE_DEVICE or clpde.use_device)")
    return 0


# ---- clpde diffuse -----------------------------------------------------------------------

@subcommand
def add_diffuse_parser(subparsers) -> None:
    from .planar import FLOWS

    parser = subparsers.add_parser(
        "diffuse", help="run a planar diffusion flow on an image",
        description="Run heat, Perona-Malik, TV or curvature diffusion for a number of "
                    "explicit steps. Colour images are processed per channel.",
    )
    add_image_arguments(parser)
    parser.add_argument("--flow", choices=FLOWS, default="heat", help="default: heat")
    parser.add_argument("--steps", type=int, default=100, help="explicit steps (default: 100)")
    parser.add_argument("--dt", type=float, default=None,
                        help="time step (default: 0.8 of the stability limit)")
    parser.add_argument("--kappa", type=float, default=None,
                        help="Perona-Malik edge threshold, intensities in [0, 1] (default 0.05)")
    parser.add_argument("--edge", choices=("exp", "rational"), default=None,
                        help="Perona-Malik edge-stopping function (default: exp)")
    parser.add_argument("--eps", type=float, default=None,
                        help="TV / curvature regularisation of |grad u| (TV default 0.05)")
    parser.set_defaults(run=run_diffuse)


def run_diffuse(args) -> int:
    from .planar import diffuse

    _param_check(args, args.flow, {"kappa": ("perona-malik",), "edge": ("perona-malik",),
                                   "eps": ("tv", "curvature")})
    image = load_input(args)
    parts = split_alpha(image, args.input)
    params = {k: getattr(args, k) for k in ("kappa", "edge", "eps") if getattr(args, k) is not None}
    result = diffuse(parts.colour, args.flow, steps=args.steps, dt=args.dt,
                     channel_axis=parts.channel_axis, device=args.device,
                     progress=show_progress(), **params)
    save_output(args, parts.join(result))
    return 0


# ---- clpde denoise -----------------------------------------------------------------------

@subcommand
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
    parser.add_argument("--eps", type=float, default=None,
                        help="--method gradient: regularisation of |grad u| (default 0.02)")
    parser.add_argument("--max-steps", type=int, default=None,
                        help="iteration cap (default: 500 primal-dual, 2000 gradient)")
    parser.set_defaults(run=run_denoise)


def run_denoise(args) -> int:
    from .rof import denoise_tv

    if args.eps is not None and args.method != "gradient":
        raise InputError("--eps applies to --method gradient only")
    image = load_input(args)
    parts = split_alpha(image, args.input)
    options = {"method": args.method}
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
    print(f"denoise: {info.steps} {args.method} iterations ({state}), residual std "
          f"{residual:.4g}", file=sys.stderr)
    return 0


# ---- clpde track -------------------------------------------------------------------------

@subcommand
def add_track_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "track", help="follow an object through video frames or image slices",
        description="Morphing active contours (thesis section 2.1): the object marked in the "
                    "first frame by --init is carried through the sequence. INPUT is a video, "
                    "a folder of images or a multi-page TIFF; colour frames are made grey. "
                    "Writes OUTDIR/mask_0000.png..., OUTDIR/overlay.gif and "
                    "OUTDIR/contours.json (polygons per frame).",
    )
    parser.add_argument("input", metavar="INPUT", help="video file, image folder or TIFF stack")
    parser.add_argument("--init", metavar="MASK", required=True,
                        help="mask image of the object in the first frame (nonzero = inside)")
    parser.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                        help="output folder (created if missing; its files are replaced)")
    parser.add_argument("--features", choices=("intensity", "edges"), default="intensity",
                        help="what the frames are compared by (default: intensity)")
    parser.add_argument("--no-equalize", action="store_true",
                        help="skip the histogram equalisation across frames")
    parser.add_argument("--no-smooth", action="store_true",
                        help="skip the anisotropic (Perona-Malik) pre-smoothing")
    parser.add_argument("--max-iterations", type=int, default=40,
                        help="cap of morphing iterations per frame (default: 40)")
    parser.add_argument("--min-size", type=int, default=0,
                        help="remove pieces and holes smaller than this many pixels (default: 0)")
    parser.add_argument("--frames", type=int, default=None, metavar="N",
                        help="use only the first N frames")
    parser.add_argument("--no-gif", action="store_true", help="do not write overlay.gif")
    add_device_argument(parser)
    parser.set_defaults(run=run_track)


def run_track(args) -> int:
    from .sequence_io import read_frames, read_mask, write_tracking
    from .track import track

    get_runtime(args.device)
    check_not_overwriting_input([args.input, args.init], args.output)
    frames = read_frames(args.input)
    if args.frames is not None:
        if args.frames < 1:
            raise InputError(f"--frames must be at least 1, not {args.frames}")
        frames = frames[: args.frames]
    mask = read_mask(args.init, frames.shape[1:3])
    masks = track(frames, mask, features=args.features, equalize=not args.no_equalize and "match",
                  smooth=not args.no_smooth, max_iterations=args.max_iterations,
                  min_size=args.min_size, device=args.device, progress=show_progress())
    written = write_tracking(args.output, frames, masks, gif=not args.no_gif)
    print(f"track: {len(masks)} frames; wrote {len(written)} files to {args.output}",
          file=sys.stderr)
    return 0


# ---- clpde inpaint -----------------------------------------------------------------------

@subcommand
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
    from .inpaint import inpaint
    from .io import write_gif

    if args.gif_every < 1:
        raise InputError(f"--gif-every must be at least 1, not {args.gif_every}")
    if args.demo:
        from .inpaint_demo import run_demo

        if args.input or args.mask or args.gif:
            raise InputError("--demo takes no IMAGE, MASK or --gif; it writes into the folder -o OUT")
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
                   "tol": args.tol, "mean_tol": args.mean_tol, "device": args.device, "progress": show_progress(),
                   "return_info": True}
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


# ---- clpde surface ------------------------------------------------------------------------

@subcommand
def add_surface_parser(subparsers) -> None:
    from .surface.demo import FLOWS, SHAPES

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
    parser.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                        help="output folder (created if missing; its files are replaced)")
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
    from .surface.demo import DATA_FLOWS, load_surface, mesh_colours, run_flow, write_run

    get_runtime(args.device)
    check_not_overwriting_input([args.mesh], args.output)
    if args.resolution < 16:
        raise InputError(f"--resolution must be at least 16, not {args.resolution}")
    if args.size < 16:
        raise InputError(f"--size must be at least 16, not {args.size}")
    if args.direction == "none" and args.flow == "flowvis":
        raise InputError("flowvis needs --direction major or minor")
    surf = load_surface(args.mesh, args.resolution, device=args.device)
    data = None
    if args.data != "pattern" and args.flow in DATA_FLOWS:
        data = mesh_colours(surf)
        if data is None and args.data == "mesh":
            raise InputError(f"{args.mesh} has no vertex colours; use --data pattern")
    run = run_flow(surf, args.flow, t=args.t, iterations=args.iterations, sigma=args.sigma,
                   seed=args.seed, direction=args.direction, data=data, progress=show_progress())
    written = write_run(run, args.output, size=args.size)
    print(f"surface {args.flow}: {run.note}; grid {'x'.join(map(str, surf.shape[::-1]))}, band "
          f"{surf.ext_band.n} cells; wrote {len(written)} files to {args.output}", file=sys.stderr)
    return 0


# ---- clpde regions -------------------------------------------------------------------------

@subcommand
def add_regions_parser(subparsers) -> None:
    from .regions_demo import FLOWS, SCENES

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
    parser.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                        help="output folder (created if missing; its files are replaced)")
    parser.add_argument("--flow", choices=FLOWS, default="gaussian",
                        help="surface motion for a mesh file (default: gaussian, the positive "
                             "part of the Gaussian curvature)")
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
    from .regions_demo import SCENES, mesh_scene, run_scene, toy_scene, write_frames

    get_runtime(args.device)
    if args.size < 16:
        raise InputError(f"--size must be at least 16, not {args.size}")
    if args.scene in SCENES:
        scene = toy_scene(args.scene, args.spacing)
        if args.t is not None:
            scene.options["t"] = args.t
    else:
        check_not_overwriting_input([args.scene], args.output)
        scene = mesh_scene(args.scene, args.flow, args.resolution, args.t, args.regions)
    frames = run_scene(scene, saves=args.saves, progress=show_progress(), device=args.device)
    written = write_frames(frames, args.output, size=args.size,
                           views=((30.0, 25.0), (-60.0, 35.0)))
    share = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
    print(f"regions {args.scene}: grid {'x'.join(map(str, scene.phi.shape[::-1]))}, region 0 "
          f"area fraction {share} at t = {', '.join(f'{f.time:g}' for f in frames)}; wrote "
          f"{len(written)} files to {args.output}", file=sys.stderr)
    return 0


# ---- entry point -------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="clpde", description="PDE image processing on OpenCL devices (GPU or CPU).")
    parser.add_argument("--version", action="version", version=f"clpde {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add_parser in SUBCOMMANDS:
        add_parser(subparsers)
    return parser


def _message(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror}{where}"
    return str(exc) or type(exc).__name__


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line for the command line's user, without the source location."""
    print(f"clpde: warning: {message}", file=sys.stderr)


def main(argv=None) -> int:
    """Run the command line; returns the exit status (0, or 2 on any error)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version and usage errors
        if exc.code is None:
            return 0
        return exc.code if isinstance(exc.code, int) else ERROR_STATUS
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            return args.run(args)
    except (ClpdeError, OSError, cl.Error) as exc:
        print(f"clpde: error: {_message(exc)}", file=sys.stderr)
        return ERROR_STATUS
    except KeyboardInterrupt:
        print("clpde: interrupted; nothing was written", file=sys.stderr)
        return 130
