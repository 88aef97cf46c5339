"""The `clpde` command line: one module per subcommand.

Each subcommand module `clpde/cli/NAME.py` has `add_NAME_parser(subparsers)`, which adds its
arguments and sets `run=<function(args) -> exit status>`; `SUBCOMMANDS` lists the names and
their one-line help in the order `--help` shows. To add a capability, write a module with
those two functions and list it below.

The modules load only when their command runs (or its `--help`): each imports its capability
(scipy, trimesh, Dask, pyopencl), which `clpde --help` need not pay. The one-line help is
therefore kept here; tests/cli/test_cli.py checks it against the modules' own.

Errors print one line `clpde: error: ...` on stderr and exit with status 2, writing nothing.
"""

from __future__ import annotations

import importlib
import sys
import warnings

from .. import _interrupt
from .._version import __version__
from ..errors import ClpdeError, error_message
from ._parser import Parser

SUBCOMMANDS = {
    "devices": "list OpenCL platforms and devices",
    "diffuse": "run a planar diffusion flow on an image",
    "denoise": "total-variation (ROF) denoising",
    "track": "follow an object through video frames or image slices",
    "inpaint": "fill a masked region of an image (structure and texture)",
    "restore": "find and fill a film's dust, dirt and scratches",
    "surface": "run a PDE on a surface given by a mesh (thesis ch. 4)",
    "regions": "track painted regions on a deforming surface (thesis 2.2)",
    "batch": "run inpaint, denoise, diffuse, track, surface or restore over many files",
}
ERROR_STATUS = 2


def add_subcommand_parser(subparsers, name: str) -> None:
    """Add subcommand `name`'s full parser (its module is imported here)."""
    module = importlib.import_module(f"{__name__}.{name}")
    getattr(module, f"add_{name}_parser")(subparsers)


def build_parser(commands=None) -> Parser:
    """The command line's parser: the subcommands in `commands` (default: all) in full, the
    others as their name and one-line help only, which is all `clpde --help` shows."""
    parser = Parser(
        prog="clpde", description="PDE image processing on OpenCL devices (GPU or CPU)."
    )
    parser.add_argument("--version", action="version", version=f"clpde {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, summary in SUBCOMMANDS.items():
        if commands is None or name in commands:
            add_subcommand_parser(subparsers, name)
        else:
            subparsers.add_parser(name, help=summary)
    return parser


def _command(argv: list[str]) -> list[str]:
    """The subcommand that `argv` runs, as a list (empty for `clpde --help`, `--version` or
    an unknown command): the top-level options take no value, so it is the first word that
    is not an option."""
    words = [word for word in argv if not word.startswith("-")]
    return words[:1] if words and words[0] in SUBCOMMANDS else []


def _reported(exc: Exception) -> bool:
    """True for the errors printed as one line: clpde's, the operating system's and
    pyopencl's (looked up only where a command has loaded pyopencl: it takes 0.3 s to import)."""
    cl = sys.modules.get("pyopencl")
    return isinstance(exc, (ClpdeError, OSError)) or (cl is not None and isinstance(exc, cl.Error))


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line for the command line's user, without the source location."""
    print(f"clpde: warning: {message}", file=sys.stderr)


def main(argv=None) -> int:
    """Run the command line; returns the exit status (0, or 2 on any error, 130 when
    interrupted)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    # The command's module loads its libraries here: still under the loading handler, since
    # a KeyboardInterrupt inside numpy's import comes out as an ImportError.
    parser = build_parser(_command(argv))
    _interrupt.restore()  # from here on, Ctrl-C is the KeyboardInterrupt caught below
    try:
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
    except KeyboardInterrupt:
        print(_interrupt.LINE, file=sys.stderr)
        return _interrupt.EXIT_STATUS
    except Exception as exc:
        if not _reported(exc):
            raise
        print(f"clpde: error: {error_message(exc)}", file=sys.stderr)
        return ERROR_STATUS


def run() -> None:
    """The `clpde` program: main() on sys.argv, exiting with its status; a Ctrl-C after
    main() has returned is ignored while Python exits."""
    status = main()
    _interrupt.ignore()
    sys.exit(status)
