"""`clpde track`: morphing active contours through frames or slices (clpde.track)."""

from __future__ import annotations

import sys

from ..imagedata import InputError
from ..io import MASK_RULE
from ..runtime import get_runtime
from ._common import (
    add_device_argument,
    add_output_folder_arguments,
    check_output_folder_args,
    show_progress,
)


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
                        help="mask image of the object in the first frame, white = inside ("
                             + MASK_RULE + ")")
    add_output_folder_arguments(parser)
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
    from ..sequence_io import read_frames, read_mask, write_tracking
    from ..track import track

    get_runtime(args.device)
    check_output_folder_args(args, [args.input, args.init])
    frames = read_frames(args.input)
    if args.frames is not None:
        if args.frames < 1:
            raise InputError(f"--frames must be at least 1, not {args.frames}")
        frames = frames[: args.frames]
    mask = read_mask(args.init, frames.shape[1:3])
    masks = track(frames, mask, features=args.features, equalize=not args.no_equalize and "match",
                  smooth=not args.no_smooth, max_iterations=args.max_iterations,
                  min_size=args.min_size, device=args.device, progress=show_progress())
    written = write_tracking(args.output, frames, masks, gif=not args.no_gif, overwrite=args.overwrite)
    print(f"track: {len(masks)} frames; wrote {len(written)} files to {args.output}",
          file=sys.stderr)
    return 0
