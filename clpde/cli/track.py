"""`clpde track`: morphing active contours through frames or slices (clpde.track)."""

from __future__ import annotations

from ..io.images import MASK_RULE
from ..scale.file_tasks import TASKS
from ..tracking.options import ADAPTIVE_ITERATIONS, ITERATIONS, TrackOptions
from ._common import add_device_argument, add_output_folder_arguments, report, show_progress


def add_track_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "track",
        help="follow an object through video frames or image slices",
        description="Morphing active contours (thesis section 2.1): the object marked in the "
        "first frame by --init is carried through the sequence. INPUT is a video, "
        "a folder of images or a multi-page TIFF; colour frames are made grey "
        "unless --colour. Frames whose final discrepancy is high are reported. "
        "Writes OUTDIR/mask_0000.png..., OUTDIR/overlay.gif and "
        "OUTDIR/contours.json (polygons per frame), and with --mp4 OUTDIR/overlay.mp4.",
    )
    parser.add_argument("input", metavar="INPUT", help="video file, image folder or TIFF stack")
    parser.add_argument(
        "--init",
        metavar="MASK",
        required=True,
        help="mask image of the object in the first frame, white = inside (" + MASK_RULE + ")",
    )
    add_output_folder_arguments(parser)
    _add_method_arguments(parser)
    _add_preprocessing_arguments(parser)
    _add_run_arguments(parser)
    _add_report_arguments(parser)
    add_device_argument(parser)
    parser.set_defaults(run=run_track)


def _add_method_arguments(parser) -> None:
    """What the frames are compared by, and how the contour's start moves."""
    parser.add_argument(
        "--features",
        choices=("intensity", "edges", "contrast"),
        default=TrackOptions.features,
        help="what the frames are compared by: grey levels, edge maps or local "
        "contrast normalisation (invariant to local light changes) "
        f"(default: {TrackOptions.features})",
    )
    parser.add_argument(
        "--colour", action="store_true", help="compare all colour channels, not grey only"
    )
    parser.add_argument(
        "--discrepancy",
        choices=("adaptive", "ncc", "difference", "huber"),
        default=TrackOptions.discrepancy,
        help="how F2 and F1 are compared: adaptive (correlation where a patch "
        "has contrast well above the noise, difference where it is flat or noisy), "
        "local normalised cross-correlation (ignores changes of light), "
        "F2 - F1 (the thesis) or a Huber-clipped difference "
        f"(default: {TrackOptions.discrepancy})",
    )
    parser.add_argument(
        "--motion",
        choices=("image", "checked", "kalman", "components", "velocity", "none"),
        default=TrackOptions.motion,
        help="start each frame at the predicted displacement: the object's motion found "
        "in the image (any speed up to 32 px a frame, with a colour appearance term that "
        "keeps the contour off the background and occluders), a constant-velocity Kalman "
        "filter fed by matching the frames checked against a wide search of the image, "
        "the filter alone, each piece matched on its own, the previous displacement, or "
        "none "
        f"(default: {TrackOptions.motion})",
    )
    parser.add_argument(
        "--shape-weight",
        type=float,
        default=TrackOptions.shape_weight,
        metavar="W",
        help="pull the contour towards the predicted start where the frames "
        f"say nothing, against leaks (e.g. 0.02; default: {TrackOptions.shape_weight:g})",
    )
    parser.add_argument(
        "--region-weight",
        type=float,
        default=None,
        metavar="W",
        help="with --discrepancy adaptive: a region term (inside and outside "
        "statistics near the contour) of this weight (the adaptive option: 1.0 "
        "with --motion components --curvature 0.3; default: off)",
    )
    parser.add_argument(
        "--curvature",
        type=float,
        default=None,
        metavar="W",
        help="with --discrepancy adaptive: a curvature term of this weight (default: off)",
    )


def _add_preprocessing_arguments(parser) -> None:
    """The frames' equalisation and smoothing before the morphing."""
    parser.add_argument(
        "--equalize",
        choices=("none", "match", "global"),
        default="none",
        help="grey-level equalisation across frames: histogram matching to "
        "the first frame, flat equalisation, or none (default: none)",
    )
    parser.add_argument(
        "--no-equalize",
        action="store_true",
        help="skip the histogram equalisation across frames (= --equalize none)",
    )
    parser.add_argument(
        "--no-smooth", action="store_true", help="skip the anisotropic (Perona-Malik) pre-smoothing"
    )


def _add_run_arguments(parser) -> None:
    """How long each frame runs, and the clean-up of its result."""
    parser.add_argument(
        "--max-iterations",
        type=int,
        default=TrackOptions.max_iterations,
        help=f"cap of morphing iterations per frame (default: {ADAPTIVE_ITERATIONS} with a "
        f"region or curvature term, {ITERATIONS} otherwise)",
    )
    parser.add_argument(
        "--min-size",
        type=int,
        default=TrackOptions.min_size,
        help="remove pieces and holes smaller than this many pixels "
        f"(default: {TrackOptions.min_size})",
    )


def _add_report_arguments(parser) -> None:
    """Which frames are used, and what is written and reported."""
    parser.add_argument(
        "--frames", type=int, default=None, metavar="N", help="use only the first N frames"
    )
    parser.add_argument("--no-gif", action="store_true", help="do not write overlay.gif")
    parser.add_argument(
        "--mp4",
        action="store_true",
        help="also write overlay.mp4 (H.264 through PyAV: pip install av; odd "
        "sizes padded by a black row or column, never rescaled)",
    )
    parser.add_argument(
        "--low-confidence",
        type=float,
        default=None,
        metavar="T",
        help="list the frames whose confidence (0 to 1, calibrated on good "
        "and lost tracks) falls below T (default: the calibrated "
        "threshold, clpde.tracking.confidence.LOW_CONFIDENCE)",
    )


def task_options(args) -> dict:
    """The track task's keywords from the parsed flags (clpde.scale.file_tasks.track_file)."""
    return {
        "features": args.features,
        "colour": args.colour,
        "discrepancy": args.discrepancy,
        "motion": args.motion,
        "shape_weight": args.shape_weight,
        "region_weight": args.region_weight,
        "curvature": args.curvature,
        "equalize": "none" if args.no_equalize else args.equalize,
        "smooth": not args.no_smooth,
        "max_iterations": args.max_iterations,
        "min_size": args.min_size,
        "frames": args.frames,
        "gif": not args.no_gif,
        "mp4": args.mp4,
        "low_confidence": args.low_confidence,
        "overwrite": args.overwrite,
        "device": args.device,
    }


def run_track(args) -> int:
    report(
        TASKS["track"](
            args.input, args.output, mask=args.init, progress=show_progress(), **task_options(args)
        )
    )
    return 0
