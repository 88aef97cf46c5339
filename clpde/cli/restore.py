"""`clpde restore`: find the dirt and scratches of a film and fill them from the neighbouring
frames (clpde.film.restore.restore_film), film in, film out."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InputError
from ..film.restore import restore_film, write_preview
from ..io.video_probe import is_video
from ..runtime import use_device
from ..scale.cluster import connect
from ..scale.file_tasks import TRANSPORT_OPTIONS
from ._common import add_device_argument


def add_film_arguments(parser) -> None:
    """The options of every film restoration (`clpde restore`; `clpde inpaint VIDEO` shares
    the running ones)."""
    group = parser.add_argument_group("running", "one process by default; Dask on request")
    cluster = group.add_mutually_exclusive_group()
    cluster.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="restore on N local Dask worker processes, in chunks of frames",
    )
    cluster.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="restore on a running Dask cluster, e.g. tcp://HOST:8786",
    )
    group.add_argument(
        "--chunk-frames",
        type=int,
        default=None,
        metavar="K",
        help="frames per Dask task (rounded up to whole windows; default 64)",
    )


def add_restore_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "restore",
        help="find and fill a film's dust, dirt and scratches",
        description="Detect the blotches and line scratches of FILM and fill them from the "
        "neighbouring frames after motion compensation (spatial inpainting where "
        "no neighbour sees the region). FILM is a film (.mp4, .mkv, .mov, .avi, "
        "...) or a folder of frames; OUT a film or a folder. A film keeps its "
        "audio (copied), subtitles, timestamps, frame rate, colour description "
        "and metadata. Memory stays bounded by a sliding window of frames.",
    )
    parser.add_argument("input", metavar="FILM", help="the film, or a folder of frames")
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUT",
        required=True,
        help="the restored film (.mp4, .mkv, .mov, .avi) or a folder",
    )
    parser.add_argument(
        "--mask",
        metavar="MASK",
        default=None,
        help="fill these masks instead of detecting: one image for every "
        "frame, or a folder of one per frame (in name order)",
    )
    parser.add_argument(
        "--masks-out",
        metavar="DIR",
        default=None,
        help="write the masks filled, one PNG per frame (mask_00000.png, ...)",
    )
    parser.add_argument(
        "--grow",
        type=float,
        default=0,
        metavar="PX",
        help="grow the masks by PX pixels (a lossy codec spreads damage 1-2 px past it; default 0)",
    )
    parser.add_argument(
        "--overlay",
        metavar="OUT.mp4",
        default=None,
        help="also write a film of the detections drawn over the frames (red: "
        "blotches, yellow: line scratches)",
    )
    parser.add_argument(
        "--codec",
        choices=("h264", "h265", "ffv1"),
        default=None,
        help="the output's codec: h264 (default), h265, or ffv1, lossless in "
        ".mkv (RGB planes: outside the masks the pixels are the input's); "
        "10-bit where the input has it",
    )
    parser.add_argument(
        "--frames",
        type=frame_range,
        default=None,
        metavar="A:B",
        help="restore only frames A to B (from 0, both included) to try a section; the "
        "frames around it are read as context, so they come out as in a run of the whole "
        "film (a section's film has no sound)",
    )
    parser.add_argument(
        "--preview",
        metavar="DIR",
        default=None,
        help="also write before|after pictures side by side (PNG) of the 3 frames with "
        "most pixels filled into DIR",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace output folders (of clpde's kinds of files only)",
    )
    add_film_arguments(parser)
    add_device_argument(parser)
    parser.set_defaults(run=run_restore)


def frame_range(text: str) -> tuple[int, int]:
    """--frames A:B as (A, B), both included (checked against the film's length later)."""
    first, sep, last = text.partition(":")
    try:
        span = (int(first), int(last))
    except ValueError:
        span = None
    if not sep or span is None or span[0] < 0 or span[1] < span[0]:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a range of frames: give A:B, from 0, with A <= B (e.g. 0:23)"
        )
    return span


def task_options(args) -> dict:
    """The restore task's keywords from the parsed flags (clpde.scale.file_tasks.restore_file):
    one film per task, in the worker's own process."""
    return {
        "masks_out": args.masks_out,
        "grow": args.grow,
        "overlay": args.overlay,
        "codec": args.codec,
        "overwrite": args.overwrite,
        "device": args.device,
        "frames": args.frames,
    }


def film_run_options(args) -> dict:
    """The running options of a film restoration from the parsed arguments: the Dask
    cluster of --workers or --scheduler, which restore_film opens once it has checked the
    inputs and outputs, and the chunks' size."""
    if args.workers is None and args.scheduler is None:
        if args.chunk_frames is not None:
            raise InputError("--chunk-frames applies with --workers or --scheduler")
        return {}
    return {"cluster": connect(args.workers, args.scheduler), "chunk_frames": args.chunk_frames}


def report(command: str, result) -> None:
    where = f"{result.workers} Dask worker(s)" if result.workers else "one process"
    rate = result.frames / result.seconds if result.seconds else 0.0
    print(
        f"{command}: {result.frames} frames ({rate:.2f} frames/s on {where}), "
        f"{result.masked_pixels} pixels filled; wrote {result.output}",
        file=sys.stderr,
    )
    most = result.most_filled(5)
    if most:
        listed = ", ".join(f"{t} ({n} px)" for t, n in most)
        print(f"{command}: frames with most pixels filled: {listed}", file=sys.stderr)


def run_restore(args) -> int:
    if args.device is not None:
        use_device(args.device)
    result = restore_film(
        args.input,
        args.output,
        mask=args.mask,
        masks_out=args.masks_out,
        grow=args.grow,
        overlay=args.overlay,
        codec=args.codec,
        overwrite=args.overwrite,
        overwrite_option="--overwrite",
        frames=args.frames,
        **film_run_options(args),
    )
    report("restore", result)
    if args.preview is not None:
        frames = [t for t, _ in result.most_filled(3)] or [result.first]
        pictures = write_preview(args.input, result.output, args.preview, frames, result.first)
        print(
            f"restore: wrote {len(pictures)} before|after pictures to {args.preview}",
            file=sys.stderr,
        )
    return 0


# ---- `clpde inpaint VIDEO --mask MASK -o OUT`: the same restoration, given the masks ------------
def add_sequence_arguments(parser) -> None:
    """The options of `clpde inpaint` for a film or a folder of frames."""
    group = parser.add_argument_group(
        "films and frame folders",
        "IMAGE may be a film or a folder of frames, restored as "
        "`clpde restore IMAGE --mask MASK` restores it; MASK (or --mask) one image or a folder "
        "of per-frame masks; -o a film or a folder",
    )
    group.add_argument(
        "--mask",
        dest="mask_option",
        metavar="MASK",
        default=None,
        help="the mask, as an option (same as the MASK argument)",
    )
    add_film_arguments(parser)


def prepare_sequence_args(args) -> bool:
    """Fold --mask into MASK; True when IMAGE is a film or a folder of frames."""
    option = getattr(args, "mask_option", None)
    if option is not None:
        if args.mask is not None:
            raise InputError("give the mask once: as MASK or as --mask")
        args.mask = option
    source = args.input
    sequence = bool(source) and (Path(source).is_dir() or is_video(source))
    if not sequence and any(
        getattr(args, name, None) is not None for name in ("workers", "scheduler", "chunk_frames")
    ):
        raise InputError(
            "--workers, --scheduler and --chunk-frames apply to a film or a folder "
            "of frames; for many image files use `clpde batch inpaint`"
        )
    return sequence


def _fill_options(args) -> dict:
    """The inpainting options given for a film (those left at their defaults are not): for
    clpde.inpaint where the neighbouring frames do not see the damage."""
    spatial = {
        name: getattr(args, name)
        for name in (*TRANSPORT_OPTIONS, "levels", "method")
        if getattr(args, name) is not None
    }
    if args.colour != "channels":
        spatial["colour"] = args.colour
    return {"spatial": spatial} if spatial else {}


def run_sequence_inpaint(args) -> int:
    """`clpde inpaint FILM --mask MASK -o OUT`: clpde.film's restoration with given masks,
    the inpainting options given on the command line passed to the filler."""
    fill_options = _fill_options(args)
    if args.gif or args.demo:
        raise InputError("--gif and --demo apply to one image, not a film or frame folder")
    if not args.mask:
        raise InputError(
            "give the mask: clpde inpaint FILM --mask MASK -o OUT (or let "
            "`clpde restore FILM -o OUT` find the damage)"
        )
    if args.device is not None:
        use_device(args.device)
    result = restore_film(
        args.input,
        args.output,
        mask=args.mask,
        fill_options=fill_options or None,
        overwrite=args.overwrite,
        overwrite_option="--overwrite",
        **film_run_options(args),
    )
    report("inpaint", result)
    return 0
