"""The `clpde` command line: one module per subcommand.

Each subcommand module has `add_parser(subparsers)`, which adds its arguments and sets
`run=<function(args) -> exit status>`; `SUBCOMMANDS` lists them in the order `--help` shows.
To add a capability, write a module with those two functions and list it below.

Errors print one line `clpde: error: ...` on stderr and exit with status 2, writing nothing.
"""

from __future__ import annotations

import sys
import warnings

import pyopencl as cl

from .. import _interrupt
from .._version import __version__
from ..errors import ClpdeError, error_message
from . import batch, denoise, devices, diffuse, inpaint, regions, restore, surface, track
from ._common import Parser

SUBCOMMANDS = [
    devices.add_devices_parser,
    diffuse.add_diffuse_parser,
    denoise.add_denoise_parser,
    track.add_track_parser,
    inpaint.add_inpaint_parser,
    restore.add_restore_parser,
    surface.add_surface_parser,
    regions.add_regions_parser,
    batch.add_batch_parser,
]
ERROR_STATUS = 2


def build_parser() -> Parser:
    parser = Parser(
        prog="clpde", description="PDE image processing on OpenCL devices (GPU or CPU)."
    )
    parser.add_argument("--version", action="version", version=f"clpde {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add_parser in SUBCOMMANDS:
        add_parser(subparsers)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line for the command line's user, without the source location."""
    print(f"clpde: warning: {message}", file=sys.stderr)


def main(argv=None) -> int:
    """Run the command line; returns the exit status (0, or 2 on any error, 130 when
    interrupted)."""
    _interrupt.restore()  # from here on, Ctrl-C is the KeyboardInterrupt caught below
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help, --version and usage errors
            if exc.code is None:
                return 0
            return exc.code if isinstance(exc.code, int) else ERROR_STATUS
        with warnings.catch_warnings():
            # Deprecations speak to Python code, not to the command line's user (Python
            # hides them outside __main__ too).
            warnings.simplefilter("ignore", DeprecationWarning)
            warnings.showwarning = _show_warning
            return args.run(args)
    except (ClpdeError, OSError, cl.Error) as exc:
        print(f"clpde: error: {error_message(exc)}", file=sys.stderr)
        return ERROR_STATUS
    except KeyboardInterrupt:
        print(_interrupt.LINE, file=sys.stderr)
        return _interrupt.EXIT_STATUS


def run() -> None:
    """The `clpde` program: main() on sys.argv, exiting with its status; a Ctrl-C after
    main() has returned is ignored while Python exits."""
    status = main()
    _interrupt.ignore()
    sys.exit(status)
