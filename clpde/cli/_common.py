"""What every subcommand shares: the device option, reading the input and writing the output.

The input is never overwritten, the output is checked before any work and written
atomically, and colour images are processed per channel with any alpha channel kept as is.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from .._progress import on_terminal as show_progress  # noqa: F401  (the subcommands' name)
from ..imagedata import InputError
from ..io import (
    check_not_overwriting_input,
    check_output_file,
    check_output_folder,
    check_writable,
    read_image,
    write_image,
)
from ..runtime import get_runtime


class Parser(argparse.ArgumentParser):
    """argparse's parser with its usage errors on one line, as every other error of the
    command line: `clpde inpaint: error: ...; see `clpde inpaint --help``, exit status 2
    (argparse's own prints the whole usage first). Its subcommands' parsers are of this
    class too (argparse makes them of the parent's)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}; see `{self.prog} --help`\n")


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


OUTPUT_FOLDER_RULE = ("created if missing (its parent must exist); it must be empty, "
                      "unless --overwrite, which replaces it as a whole")


def add_output_folder_arguments(parser, what: str = "output folder") -> None:
    """-o/--output OUTDIR and --overwrite, with the one rule of every folder-writing command."""
    parser.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                        help=f"{what}: {OUTPUT_FOLDER_RULE}")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace the output folder's contents (only a folder of clpde's "
                             "kinds of output files: .png .gif .json .ply .glb .tif .jpg)")


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
            text = re.sub(r"use a finer spacing \(below [^)]*\) or a narrower band",
                          f"give a larger --resolution (such as {2 * resolution}, which halves "
                          "the spacing)", text)
        warnings.warn(text, w.category, stacklevel=3)


def load_input(args, *extra_inputs, allow_nan: bool = False) -> np.ndarray:
    """Check the device and the output path, then read IN; all before any work is done.
    NaN pixels are refused with the command that fills them, unless allow_nan."""
    get_runtime(args.device)  # an unknown device fails here, before reading anything
    check_not_overwriting_input([args.input, *extra_inputs], args.output)
    check_output_file(args.output)  # before reading: a large input takes a while
    image = read_image(args.input)
    if image.dtype == bool:  # 1-bit files: compute on 0/255 and write 8-bit
        image = image.astype(np.uint8) * 255
    if not allow_nan and np.issubdtype(image.dtype, np.floating):
        bad = int((~np.isfinite(image)).sum())
        if bad:
            raise InputError(
                f"{args.input} has {bad} NaN or infinite values; fill them first with "
                f"`clpde inpaint {args.input} nan -o FILLED.tif`, then use FILLED.tif")
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


def param_check(args, flow: str, allowed: dict) -> None:
    """Refuse options that the chosen flow would silently ignore."""
    for option, flows in allowed.items():
        if getattr(args, option) is not None and flow not in flows:
            raise InputError(f"--{option} applies to --flow {' or '.join(flows)}, not {flow}")
