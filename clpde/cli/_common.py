"""What every subcommand shares: the device option, reading the input and writing the output.

The input is never overwritten, the output is checked before any work and written
atomically, and colour images are processed per channel with any alpha channel kept as is.
"""

from __future__ import annotations

import contextlib
import re
import sys
import warnings

from .._progress import on_terminal as show_progress  # noqa: F401  (the subcommands' name)
from ..errors import InputError
from ..imagedata import Channels, split_alpha  # noqa: F401  (the subcommands' names)
from ..io.images import (
    check_not_overwriting_input,
    check_output_folder,
)


def add_device_argument(parser) -> None:
    parser.add_argument(
        "--device",
        metavar="SPEC",
        default=None,
        help="OpenCL device: 'cpu', 'gpu', an index or a name substring from `clpde devices` "
        "(default: $CLPDE_DEVICE, else a GPU if present, else the CPU)",
    )


def add_image_arguments(parser) -> None:
    """IN and OUT paths (OUT given as the second word or as -o OUT) and --device."""
    parser.add_argument("input", metavar="IN", help="input image (.png, .tif/.tiff, .jpg/.jpeg)")
    parser.add_argument(
        "output",
        metavar="OUT",
        nargs="?",
        help="output image; same formats; never the input file",
    )
    parser.add_argument(
        "-o", "--output", dest="output_flag", metavar="OUT", help="the output, as a flag"
    )
    add_device_argument(parser)


def output_path(args) -> str:
    """OUT of add_image_arguments, given once either way (one line otherwise)."""
    if (args.output is None) == (args.output_flag is None):
        given = "both OUT and -o" if args.output else "no output"
        raise InputError(f"{given}: give the output once, as OUT or as -o OUT")
    return args.output or args.output_flag


OUTPUT_FOLDER_RULE = (
    "created if missing (its parent must exist); it must be empty, "
    "unless --overwrite, which replaces it as a whole"
)


def add_output_folder_arguments(parser, what: str = "output folder") -> None:
    """-o/--output OUTDIR and --overwrite, with the one rule of every folder-writing command."""
    parser.add_argument(
        "-o", "--output", metavar="OUTDIR", required=True, help=f"{what}: {OUTPUT_FOLDER_RULE}"
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the output folder's contents (only a folder of clpde's "
        "kinds of output files: .png .gif .json .ply .glb .tif .jpg)",
    )


def check_output_folder_args(args, inputs=()) -> None:
    """The output folder's checks, before any work: not an input, and the folder rule."""
    check_not_overwriting_input(list(inputs), args.output)
    check_output_folder(args.output, args.overwrite, option="--overwrite")


# Below this share of the band on a medial axis the flows' loss of accuracy is negligible.
_COARSE_SHARE_SHOWN = 0.1  # percent


@contextlib.contextmanager
def grid_advice(resolution: int):
    """The surface library's warnings in command-line terms: its grid is set by
    --resolution (cells across the longest side), not by a spacing."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        finally:
            pending = list(caught)
    for w in pending:
        text = str(w.message)
        if "use a finer spacing" in text:
            share = re.search(r"([\d.]+)% of the band", text)
            if share and float(share.group(1)) < _COARSE_SHARE_SHOWN:
                continue
            text = re.sub(
                r"use a finer spacing \(below [^)]*\) or a narrower band",
                f"give a larger --resolution (such as {2 * resolution}, which halves the spacing)",
                text,
            )
        warnings.warn(text, w.category, stacklevel=3)


def report(lines) -> None:
    """A task's report (clpde.scale.file_tasks), one line each on stderr."""
    for line in lines:
        print(line, file=sys.stderr)


def param_check(args, flow: str, allowed: dict) -> None:
    """Refuse options that the chosen flow would silently ignore."""
    for option, flows in allowed.items():
        if getattr(args, option) is not None and flow not in flows:
            raise InputError(f"--{option} applies to --flow {' or '.join(flows)}, not {flow}")
