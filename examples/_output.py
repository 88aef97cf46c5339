"""Where the examples write: out/ (git-ignored) by default, or another folder with --out;
the documentation's pictures (docs/images, shown by the README) only with --docs."""

from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs" / "images"


def add_output_arguments(parser, default="out") -> None:
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help=f"output folder, created if missing (default: {default}/)",
    )
    parser.add_argument(
        "--docs",
        action="store_true",
        help=f"write the documentation pictures into {DOCS} instead, "
        "replacing the README's pictures",
    )
    parser.set_defaults(default_out=Path(default))


def output_folder(parser, args) -> Path:
    """The folder to write into, created (with its parents) if missing."""
    if args.docs and args.out is not None:
        parser.error("give --out or --docs, not both")
    folder = DOCS if args.docs else args.out if args.out is not None else args.default_out
    folder.mkdir(parents=True, exist_ok=True)
    return folder
